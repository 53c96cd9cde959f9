//! One way to run a network of either family on a dataset's frames: the paper's network
//! through its lookup tables ([`Inference`]), the cascade through its per-pixel sampler
//! ([`CascadeInference`]) with the learnt pick after it when one is set ([`PickedCascade`]),
//! all behind the workspace's one depth interface, [`DepthEstimator`], answering with a
//! [`DepthEstimate`] on their output grid.
//!
//! The pick chain is composed here, above both: the cascade answers ([`CascadeAnswer`]), the
//! coarse modes the pick asks for are read from that answer ([`coarse_modes`]), and the pick
//! ([`PickRefiner`]) replaces the index map.

use std::time::Instant;

use burn::tensor::Device;
use omnimvs_camera::ValidityMask;
use omnimvs_core::GrayImage;
use omnimvs_data::{Dataset, DepthEstimate, DepthEstimator, EstimateError, StageObserver};
use omnimvs_sweep::{CacheStatus, EquirectGrid, InvDepthHypotheses, LutCache, SweepSpec};

use crate::bundled::PickChoice;
use crate::cascade::{CascadeAnswer, CascadeInference, StageOutput};
use crate::config::NetConfig;
use crate::error::NetError;
use crate::hostconv;
use crate::infer::Inference;
use crate::pick::{CoarseModes, PickRefiner};
use crate::tensor::read_values;
use crate::weights::AnyNet;

/// A network of either family, prepared for one rig.
pub enum NetEstimator {
    /// The paper's network.
    OmniMvs(Box<Inference>),
    /// The coarse-to-fine network, with the learnt pick after it when one is set.
    Cascade(Box<PickedCascade>),
}

impl NetEstimator {
    /// Prepares `net` for `dataset` on `device`: batch norms folded (both families), the
    /// paper's network's lookup table from `cache` (its status is returned), and its sweep or
    /// the cascade's correlation on the device when `sweep_on_device` (GPU backends), on the
    /// host otherwise; on burn flex, the convolutions on the host kernels too
    /// ([`crate::hostconv`]).
    ///
    /// # Errors
    /// [`NetError`] when the rig does not fit the network or a table cannot be built.
    pub fn new(
        net: AnyNet,
        dataset: &Dataset,
        cache: &LutCache,
        device: Device,
        sweep_on_device: bool,
    ) -> Result<(Self, Option<CacheStatus>), NetError> {
        let host_convs = !sweep_on_device && hostconv::pays_on(&device);
        Ok(match net {
            AnyNet::OmniMvs(net) => {
                let net = if host_convs {
                    (*net).fold_batch_norm().with_host_convs()
                } else {
                    (*net).fold_batch_norm()
                };
                let (mut inference, status) = Inference::new(net, dataset, cache, device)?;
                if sweep_on_device {
                    inference.sweep_on_device();
                }
                (Self::OmniMvs(Box::new(inference)), Some(status))
            }
            AnyNet::Cascade(net) => (
                Self::Cascade(Box::new(PickedCascade::new(CascadeInference::new(
                    if host_convs {
                        (*net).fold_batch_norm().with_host_convs()
                    } else {
                        (*net).fold_batch_norm()
                    },
                    dataset,
                    device,
                    !sweep_on_device,
                )?))),
                None,
            ),
        })
    }

    /// Runs the learnt `pick` after the network ([`crate::pick`]; the cascade only).
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] for the paper's network, [`NetError::Shape`] for a pick made
    /// for another number of cameras.
    pub fn with_pick(self, pick: PickRefiner) -> Result<Self, NetError> {
        match self {
            Self::Cascade(i) => Ok(Self::Cascade(Box::new((*i).with_pick(pick)?))),
            Self::OmniMvs(_) => Err(NetError::InvalidConfig {
                field: "pick",
                message: "the learnt pick runs after the cascade network only".into(),
            }),
        }
    }

    /// Whether the learnt pick runs after the network.
    pub fn has_pick(&self) -> bool {
        matches!(self, Self::Cascade(i) if i.has_pick())
    }

    /// The network with the pick `choice` loaded (`pick`, `None` for none): the picks read
    /// each camera's colour in a channel of their own and run on rigs of the camera count they
    /// were trained on, so under [`PickChoice::Auto`] a pick made for another count stands
    /// aside, and the note returned says so.
    ///
    /// # Errors
    /// As [`Self::with_pick`], for a pick chosen by name or file.
    pub fn with_chosen_pick(
        self,
        choice: &PickChoice,
        pick: Option<PickRefiner>,
    ) -> Result<(Self, Option<String>), NetError> {
        let cameras = self.order().len();
        match pick {
            Some(pick) if pick.cameras() != cameras && *choice == PickChoice::Auto => {
                let note = format!(
                    "the bundled picks read {} cameras and this rig has {cameras}: answering \
                     without them (--pick off)",
                    pick.cameras()
                );
                Ok((self, Some(note)))
            }
            Some(pick) => Ok((self.with_pick(pick)?, None)),
            None => Ok((self, None)),
        }
    }

    /// The network's configuration.
    pub fn config(&self) -> &NetConfig {
        match self {
            Self::OmniMvs(i) => &i.net().config,
            Self::Cascade(i) => &i.inference().net().config,
        }
    }

    /// The output grid and the dataset's `N` hypotheses.
    pub fn spec(&self) -> &SweepSpec {
        match self {
            Self::OmniMvs(i) => i.spec(),
            Self::Cascade(i) => i.inference().spec(),
        }
    }

    /// The output grid.
    pub fn grid(&self) -> &EquirectGrid {
        &self.spec().grid
    }

    /// The dataset's `N` hypotheses.
    pub fn hypotheses(&self) -> &InvDepthHypotheses {
        &self.spec().hypotheses
    }

    /// Validity masks of the cameras.
    pub fn masks(&self) -> &[ValidityMask] {
        match self {
            Self::OmniMvs(i) => i.masks(),
            Self::Cascade(i) => i.inference().masks(),
        }
    }

    /// Sets the paper's network's camera concatenation order (the cascade has none: its
    /// correlation does not depend on the order).
    ///
    /// # Errors
    /// [`NetError::CameraOrder`] for an order that is not a permutation, or any order for
    /// the cascade.
    pub fn set_order(&mut self, order: &[usize]) -> Result<(), NetError> {
        match self {
            Self::OmniMvs(i) => i.set_order(order),
            Self::Cascade(_) => Err(NetError::InvalidConfig {
                field: "order",
                message: "the cascade network has no camera order".into(),
            }),
        }
    }

    /// The camera concatenation order (the rig's for the cascade).
    pub fn order(&self) -> Vec<usize> {
        match self {
            Self::OmniMvs(i) => i.order().to_vec(),
            Self::Cascade(i) => (0..i.inference().full_sampler().num_cameras()).collect(),
        }
    }
}

/// The cascade with the learnt pick after it when one is set ([`crate::pick`]): the pick runs
/// on the cascade's answer, with the coarse stage's modes it reads.
pub struct PickedCascade {
    inference: CascadeInference,
    pick: Option<PickRefiner>,
}

impl PickedCascade {
    /// The cascade alone, without a pick.
    pub fn new(inference: CascadeInference) -> Self {
        Self {
            inference,
            pick: None,
        }
    }

    /// Runs `pick` after the network on every frame ([`crate::pick`]; it was trained on one
    /// network's answers: the bundled pick on the bundled cascade's).
    ///
    /// # Errors
    /// [`NetError::Shape`] when the pick was made for another number of cameras than the rig's.
    pub fn with_pick(mut self, pick: PickRefiner) -> Result<Self, NetError> {
        let cameras = self.inference.full_sampler().num_cameras();
        if pick.cameras() != cameras {
            return Err(NetError::Shape {
                what: "pick: cameras of the rig".into(),
                expected: vec![pick.cameras()],
                actual: vec![cameras],
            });
        }
        self.pick = Some(pick);
        Ok(self)
    }

    /// The cascade.
    pub fn inference(&self) -> &CascadeInference {
        &self.inference
    }

    /// Whether the learnt pick runs after the network.
    pub fn has_pick(&self) -> bool {
        self.pick.is_some()
    }

    /// Runs the network, then the pick when one is set, on one frame's gray images (rig
    /// order); each stage's time (the pick's as `pick`) given to `observer` when it wants them.
    ///
    /// # Errors
    /// [`NetError`] for a wrong number of images or a mask of another size.
    pub fn run(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
    ) -> Result<DepthEstimate, NetError> {
        self.run_with_modes(images, observer, 0)
            .map(|(estimate, _)| estimate)
    }

    /// [`Self::run`], with the coarse stage's `modes` most probable modes on the output grid
    /// ([`CoarseModes`]; none for 0). The pick reads those its layout asks for whatever
    /// `modes` is; this is for the data a pick trains on.
    ///
    /// # Errors
    /// As [`Self::run`].
    pub fn run_with_modes(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
        modes: usize,
    ) -> Result<(DepthEstimate, CoarseModes), NetError> {
        let mut answer = self.inference.answer(images, observer.wants_timings())?;
        let start = Instant::now();
        let wanted = modes.max(self.pick.as_ref().map_or(0, PickRefiner::coarse_modes));
        let coarse_modes = coarse_modes(&answer.coarse, wanted, self.inference.grid())?;
        let modes_seconds = start.elapsed().as_secs_f64();
        if let Some(pick) = &self.pick {
            let start = Instant::now();
            answer.index = self.refine(pick, &answer, &coarse_modes, images)?;
            let seconds = start.elapsed().as_secs_f64() + modes_seconds;
            answer.stages.push(("pick", seconds));
            answer.seconds += seconds;
        }
        Ok((self.inference.estimate(answer, observer), coarse_modes))
    }

    /// `pick`'s index map (`N` units, output grid) from the cascade's `answer`.
    fn refine(
        &self,
        pick: &PickRefiner,
        answer: &CascadeAnswer,
        modes: &CoarseModes,
        images: &[GrayImage],
    ) -> Result<Vec<f32>, NetError> {
        let sampler = self.inference.full_sampler();
        pick.refine(&answer.index, &answer.spread, modes, sampler, images)
    }
}

/// The `count` most probable modes of a coarse stage's distribution on the output `grid`
/// ([`CoarseModes::from_distribution`]; none for 0).
///
/// # Errors
/// [`NetError`] when the stage's tensors cannot be read.
pub fn coarse_modes(
    coarse: &StageOutput,
    count: usize,
    grid: &EquirectGrid,
) -> Result<CoarseModes, NetError> {
    if count == 0 {
        return Ok(CoarseModes::none());
    }
    let [_, k, h, w] = coarse.prob.dims();
    CoarseModes::from_distribution(
        &read_values(coarse.prob.clone(), "coarse distribution")?,
        &read_values(coarse.hypotheses.clone(), "coarse spheres")?,
        [k, h, w],
        count,
        [grid.height, grid.width],
    )
}

impl From<NetError> for EstimateError {
    fn from(e: NetError) -> Self {
        Self::new(e)
    }
}

impl DepthEstimator for NetEstimator {
    fn name(&self) -> &str {
        match self {
            Self::OmniMvs(_) => Inference::NAME,
            Self::Cascade(_) => CascadeInference::NAME,
        }
    }

    fn spec(&self) -> &SweepSpec {
        NetEstimator::spec(self)
    }

    /// Stages are timed, and the device waited for after each, only when `observer` wants
    /// them.
    fn estimate_observed(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
    ) -> Result<DepthEstimate, EstimateError> {
        Ok(match self {
            Self::OmniMvs(i) => i.run_observed(images, observer)?,
            Self::Cascade(i) => i.run(images, observer)?,
        })
    }
}
