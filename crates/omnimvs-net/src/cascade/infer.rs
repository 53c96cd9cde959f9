//! The cascade on a dataset's frames: the rig's geometry once, then per frame the inputs
//! (normalised over the valid pixels, resized to the network's input), the forward pass and
//! the maps of the final stage.

use burn::tensor::Device;
use omnimvs_camera::ValidityMask;
use omnimvs_data::{Dataset, DepthEstimate, StageObserver};
use omnimvs_sweep::{EquirectGrid, GrayImage, InvDepthHypotheses, SweepSpec};

use super::geometry::CascadeGeometry;
use super::model::CascadeNet;
use crate::error::NetError;
use crate::infer::{entropy_estimate, input_tensors, sweep_spec};

/// A cascade network ready to run on the frames of one rig.
pub struct CascadeInference {
    net: CascadeNet,
    geometry: CascadeGeometry,
    spec: SweepSpec,
    masks: Vec<ValidityMask>,
    device: Device,
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

    /// Runs the network on one frame's gray images (rig order): the final stage's maps, each
    /// stage's time given to `observer` when it wants them (the device is then waited for
    /// after each stage).
    ///
    /// # Errors
    /// [`NetError`] for a wrong number of images or a mask of another size.
    pub fn run(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
    ) -> Result<DepthEstimate, NetError> {
        let inputs = input_tensors(&self.net.config, images, &self.masks, &self.device)?;
        let timed = observer.wants_timings();
        let (out, t) = self.net.forward_timed(&inputs, &self.geometry, timed)?;
        let [_, _, fine] = out.stages;
        observer.stages(&[
            ("features", t.features),
            ("coarse", t.coarse),
            ("mid", t.mid),
            ("fine", t.fine),
            ("total", t.total),
        ]);
        entropy_estimate(self.spec, Self::NAME, fine.entropy(), fine.index, t.total)
    }
}
