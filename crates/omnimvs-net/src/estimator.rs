//! One way to run a network of either family on a dataset's frames: the paper's network
//! through its lookup tables ([`Inference`]), the cascade through its per-pixel sampler
//! ([`CascadeInference`]), both behind the workspace's one depth interface,
//! [`DepthEstimator`], answering with a [`DepthEstimate`] on their output grid.

use burn::tensor::Device;
use omnimvs_camera::ValidityMask;
use omnimvs_data::{Dataset, DepthEstimate, DepthEstimator, EstimateError, StageObserver};
use omnimvs_sweep::{
    CacheStatus, EquirectGrid, GrayImage, InvDepthHypotheses, LutCache, SweepSpec,
};

use crate::cascade::CascadeInference;
use crate::config::NetConfig;
use crate::error::NetError;
use crate::hostconv;
use crate::infer::Inference;
use crate::pick::PickRefiner;
use crate::weights::AnyNet;

/// A network of either family, prepared for one rig.
pub enum NetEstimator {
    /// The paper's network.
    OmniMvs(Box<Inference>),
    /// The coarse-to-fine network.
    Cascade(Box<CascadeInference>),
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
                Self::Cascade(Box::new(CascadeInference::new(
                    if host_convs {
                        (*net).fold_batch_norm().with_host_convs()
                    } else {
                        (*net).fold_batch_norm()
                    },
                    dataset,
                    device,
                    !sweep_on_device,
                )?)),
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
            Self::Cascade(i) => Ok(Self::Cascade(Box::new(i.with_pick(pick)?))),
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

    /// The network's configuration.
    pub fn config(&self) -> &NetConfig {
        match self {
            Self::OmniMvs(i) => &i.net().config,
            Self::Cascade(i) => &i.net().config,
        }
    }

    /// The output grid and the dataset's `N` hypotheses.
    pub fn spec(&self) -> &SweepSpec {
        match self {
            Self::OmniMvs(i) => i.spec(),
            Self::Cascade(i) => i.spec(),
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
            Self::Cascade(i) => i.masks(),
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
            Self::Cascade(i) => (0..i.net().config.num_cameras).collect(),
        }
    }
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
