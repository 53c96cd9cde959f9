//! The cascade on a dataset's frames: the rig's geometry once, then per frame the inputs
//! (normalised over the valid pixels, resized to the network's input), the forward pass, the
//! final stage's index map and the coarse stage's entropy and spread as the estimate's
//! uncertainty.

use burn::tensor::Device;
use omnimvs_camera::ValidityMask;
use omnimvs_core::GrayImage;
use omnimvs_data::{Dataset, DepthEstimate, StageObserver};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, SweepSpec, resample_map};

use super::geometry::CascadeGeometry;
use super::model::{CascadeNet, StageOutput};
use crate::error::NetError;
use crate::infer::{input_tensors, sweep_spec};
use crate::pixel::PixelSampler;
use crate::tensor::read_values;

/// A cascade network ready to run on the frames of one rig.
pub struct CascadeInference {
    net: CascadeNet,
    geometry: CascadeGeometry,
    spec: SweepSpec,
    masks: Vec<ValidityMask>,
    device: Device,
}

/// The cascade's answer on one frame before it becomes an estimate: what the learnt pick
/// after the network reads ([`crate::estimator::PickedCascade`]). Maps are row-major on the
/// output grid.
pub struct CascadeAnswer {
    /// The final stage's index map (`N` units).
    pub index: Vec<f32>,
    /// The coarse stage's entropy (nats), resampled to the output grid.
    pub entropy: Vec<f32>,
    /// The coarse stage's spread: the standard deviation of its distribution around its soft
    /// argmax (`N` units), resampled to the output grid.
    pub spread: Vec<f32>,
    /// The coarse stage's output, on its own grid.
    pub coarse: StageOutput,
    /// Each stage's time (seconds), in order: `features`, `coarse`, `mid`, `fine`.
    pub stages: Vec<(&'static str, f64)>,
    /// The time of the whole answer (seconds).
    pub seconds: f64,
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
        })
    }

    /// The full-resolution stage's per-pixel sampler: the output grid projected into the
    /// rig's cameras, which the pick reads the images through too.
    pub fn full_sampler(&self) -> &PixelSampler {
        &self.geometry.samplers[2]
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
    /// after each stage). The estimate's entropy and spread are the coarse stage's
    /// ([`Self::answer`]).
    ///
    /// # Errors
    /// [`NetError`] for a wrong number of images or a mask of another size.
    pub fn run(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
    ) -> Result<DepthEstimate, NetError> {
        let answer = self.answer(images, observer.wants_timings())?;
        Ok(self.estimate(answer, observer))
    }

    /// The network's answer on one frame's gray images (rig order), each stage timed when
    /// `timed` (the device is then waited for after each stage). The entropy and spread
    /// (standard deviation, `N` units) are the coarse stage's, over its spheres across the
    /// whole range, resampled to the output grid: the refinement stages' own distributions span
    /// a few index units around their centres and say nothing of a gross miss (on things
    /// validation frames, leaving out the tenth of the pixels with the highest full-resolution
    /// entropy raises the MAE of the rest, 4.33 -> 4.53; by the coarse entropy it falls to
    /// 3.21, by the spread to 2.97; `research/errors.md`).
    ///
    /// # Errors
    /// [`NetError`] for a wrong number of images or a mask of another size.
    pub fn answer(&self, images: &[GrayImage], timed: bool) -> Result<CascadeAnswer, NetError> {
        let inputs = input_tensors(&self.net.config, images, &self.masks, &self.device)?;
        let (out, t) = self.net.forward_timed(&inputs, &self.geometry, timed)?;
        let [coarse, _, fine] = out.stages;
        let coarse_grid = *self.geometry.samplers[0].grid();
        let on_grid = |map: Vec<f32>| resample_map(&map, &coarse_grid, &self.spec.grid);
        let entropy = on_grid(read_values(coarse.entropy(), "coarse entropy map")?);
        // The coarse distribution's standard deviation around its soft argmax, N units.
        let offsets = coarse.hypotheses.clone() - coarse.index.clone().unsqueeze_dim::<4>(1);
        let variance = (coarse.prob.clone() * offsets.clone() * offsets)
            .sum_dim(1)
            .squeeze_dim::<3>(1);
        let spread = on_grid(read_values(
            variance.clamp_min(0.0).sqrt(),
            "coarse spread map",
        )?);
        let index = read_values(fine.index, "index map")?;
        Ok(CascadeAnswer {
            index,
            entropy,
            spread,
            coarse,
            stages: vec![
                ("features", t.features),
                ("coarse", t.coarse),
                ("mid", t.mid),
                ("fine", t.fine),
            ],
            seconds: t.total,
        })
    }

    /// The estimate of `answer` (its index map, the coarse stage's entropy and spread, its
    /// time); its stages' times and the total given to `observer`.
    pub fn estimate(
        &self,
        answer: CascadeAnswer,
        observer: &mut dyn StageObserver,
    ) -> DepthEstimate {
        let CascadeAnswer {
            index,
            entropy,
            spread,
            mut stages,
            seconds,
            ..
        } = answer;
        stages.push(("total", seconds));
        observer.stages(&stages);
        DepthEstimate {
            spread: Some(spread),
            ..DepthEstimate::with_entropy(self.spec, Self::NAME, index, entropy, seconds)
        }
    }
}
