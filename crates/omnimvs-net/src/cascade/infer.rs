//! The cascade on a dataset's frames: the rig's geometry once, then per frame the inputs
//! (normalised over the valid pixels, resized to the network's input), the forward pass, the
//! final stage's index map and the coarse stage's entropy and spread as the estimate's
//! uncertainty.

use std::time::Instant;

use burn::tensor::Device;
use omnimvs_camera::ValidityMask;
use omnimvs_data::{Dataset, DepthEstimate, StageObserver};
use omnimvs_sweep::{EquirectGrid, GrayImage, InvDepthHypotheses, SweepSpec, resample_map};

use super::geometry::CascadeGeometry;
use super::model::{CascadeNet, StageOutput};
use super::sampler::PixelSampler;
use crate::error::NetError;
use crate::infer::{input_tensors, sweep_spec};
use crate::pick::{CoarseModes, PickRefiner};
use crate::tensor::read_values;

/// A cascade network ready to run on the frames of one rig.
pub struct CascadeInference {
    net: CascadeNet,
    geometry: CascadeGeometry,
    spec: SweepSpec,
    masks: Vec<ValidityMask>,
    device: Device,
    /// The learnt pick after the network ([`crate::pick`]), when set.
    pick: Option<PickRefiner>,
}

impl CascadeInference {
    /// The method's name in estimates.
    pub const NAME: &'static str = "cascade";

    /// Prepares `net` for `dataset`'s rig on `device`; the stages correlate on the host when
    /// `host_correlation` (CPU backends, see [`CascadeGeometry::with_host_correlation`]).
    ///
    /// # Errors
    /// [`NetError`] when the rig does not fit the network or the masks cannot be read.
    pub fn new(
        net: CascadeNet,
        dataset: &Dataset,
        device: Device,
        host_correlation: bool,
    ) -> Result<Self, NetError> {
        let spec = sweep_spec(&net.config, dataset)?;
        let geometry = CascadeGeometry::with_host_correlation(
            &dataset.rig,
            &net.config,
            &spec.hypotheses,
            &device,
            host_correlation,
        )?;
        Ok(Self {
            net,
            geometry,
            spec,
            masks: dataset.masks()?,
            device,
            pick: None,
        })
    }

    /// Runs `pick` after the network on every frame ([`crate::pick`]; it was trained on one
    /// network's answers: the bundled pick on the bundled cascade's).
    ///
    /// # Errors
    /// [`NetError::Shape`] when the pick was made for another number of cameras than the rig's.
    pub fn with_pick(mut self, pick: PickRefiner) -> Result<Self, NetError> {
        let cameras = self.full_sampler().num_cameras();
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

    /// The full-resolution stage's per-pixel sampler: the output grid projected into the
    /// rig's cameras, which the pick reads the images through too.
    fn full_sampler(&self) -> &PixelSampler {
        &self.geometry.samplers[2]
    }

    /// Whether the learnt pick runs after the network.
    pub fn has_pick(&self) -> bool {
        self.pick.is_some()
    }

    /// The network.
    pub fn net(&self) -> &CascadeNet {
        &self.net
    }

    /// The output grid and the dataset's hypotheses.
    pub fn spec(&self) -> &SweepSpec {
        &self.spec
    }

    /// The output grid.
    pub fn grid(&self) -> &EquirectGrid {
        &self.spec.grid
    }

    /// The `N` hypotheses of the dataset.
    pub fn hypotheses(&self) -> &InvDepthHypotheses {
        &self.geometry.hypotheses
    }

    /// Validity masks of the cameras at the dataset's image size.
    pub fn masks(&self) -> &[ValidityMask] {
        &self.masks
    }

    /// Runs the network on one frame's gray images (rig order): the final stage's index map,
    /// each stage's time given to `observer` when it wants them (the device is then waited for
    /// after each stage). The estimate's entropy and spread (standard deviation, `N` units) are
    /// the coarse stage's, over its spheres across the whole range, resampled to the output
    /// grid: the refinement stages' own distributions span a few index units around their
    /// centres and say nothing of a gross miss (on things validation frames, leaving out the
    /// tenth of the pixels with the highest full-resolution entropy raises the MAE of the rest,
    /// 4.33 -> 4.53; by the coarse entropy it falls to 3.21, by the spread to 2.97;
    /// `research/errors.md`).
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
    /// ([`CoarseModes`]; none for 0). The learnt pick reads them itself when its layout asks
    /// for them; this is for the data a pick trains on.
    ///
    /// # Errors
    /// As [`Self::run`].
    pub fn run_with_modes(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
        modes: usize,
    ) -> Result<(DepthEstimate, CoarseModes), NetError> {
        let inputs = input_tensors(&self.net.config, images, &self.masks, &self.device)?;
        let timed = observer.wants_timings();
        let (out, t) = self.net.forward_timed(&inputs, &self.geometry, timed)?;
        let [coarse, _, fine] = out.stages;
        let coarse_grid = *self.geometry.samplers[0].grid();
        let on_grid = |map: Vec<f32>| resample_map(&map, &coarse_grid, &self.spec.grid);
        let entropy = on_grid(read_values(coarse.entropy(), "coarse entropy map")?);
        let start = Instant::now();
        let wanted = modes.max(self.pick.as_ref().map_or(0, PickRefiner::coarse_modes));
        let coarse_modes = coarse_modes(&coarse, wanted, &self.spec.grid)?;
        let modes_seconds = start.elapsed().as_secs_f64();
        // The coarse distribution's standard deviation around its soft argmax, N units.
        let offsets = coarse.hypotheses - coarse.index.unsqueeze_dim::<4>(1);
        let variance = (coarse.prob * offsets.clone() * offsets)
            .sum_dim(1)
            .squeeze_dim::<3>(1);
        let spread = on_grid(read_values(
            variance.clamp_min(0.0).sqrt(),
            "coarse spread map",
        )?);
        let mut index = read_values(fine.index, "index map")?;
        let mut total = t.total;
        let mut stages = vec![
            ("features", t.features),
            ("coarse", t.coarse),
            ("mid", t.mid),
            ("fine", t.fine),
        ];
        if let Some(pick) = &self.pick {
            let start = Instant::now();
            index = pick.refine(&index, &spread, &coarse_modes, self.full_sampler(), images)?;
            let seconds = start.elapsed().as_secs_f64() + modes_seconds;
            stages.push(("pick", seconds));
            total += seconds;
        }
        stages.push(("total", total));
        observer.stages(&stages);
        Ok((
            DepthEstimate {
                spread: Some(spread),
                ..DepthEstimate::with_entropy(self.spec, Self::NAME, index, entropy, total)
            },
            coarse_modes,
        ))
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
