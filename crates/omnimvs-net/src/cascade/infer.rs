//! The cascade on a dataset's frames: the rig's geometry once, then per frame the inputs
//! (normalised over the valid pixels, resized to the network's input), the forward pass and
//! the maps of the final stage.

use burn::tensor::Device;
use omnimvs_camera::ValidityMask;
use omnimvs_data::Dataset;
use omnimvs_sweep::{EquirectGrid, GrayImage, InvDepthHypotheses};

use super::geometry::{CascadeGeometry, CascadeTimings};
use super::model::{CascadeNet, read_values};
use crate::error::NetError;
use crate::infer::{FrameResult, input_tensors, sweep_geometry};

/// A cascade network ready to run on the frames of one rig.
pub struct CascadeInference {
    net: CascadeNet,
    geometry: CascadeGeometry,
    grid: EquirectGrid,
    masks: Vec<ValidityMask>,
    device: Device,
}

impl CascadeInference {
    /// Prepares `net` for `dataset`'s rig on `device`.
    ///
    /// # Errors
    /// [`NetError`] when the rig does not fit the network or the masks cannot be read.
    pub fn new(net: CascadeNet, dataset: &Dataset, device: Device) -> Result<Self, NetError> {
        let (grid, hypotheses) = sweep_geometry(&net.config, dataset)?;
        let geometry = CascadeGeometry::new(&dataset.rig, &net.config, &hypotheses, &device)?;
        Ok(Self {
            net,
            geometry,
            grid,
            masks: dataset.masks()?,
            device,
        })
    }

    /// The network.
    pub fn net(&self) -> &CascadeNet {
        &self.net
    }

    /// The output grid.
    pub fn grid(&self) -> &EquirectGrid {
        &self.grid
    }

    /// The `N` hypotheses of the dataset.
    pub fn hypotheses(&self) -> &InvDepthHypotheses {
        &self.geometry.hypotheses
    }

    /// Validity masks of the cameras at the dataset's image size.
    pub fn masks(&self) -> &[ValidityMask] {
        &self.masks
    }

    /// Runs the network on one frame's gray images (rig order): the final stage's maps, and
    /// each stage's time when `timed` (which waits for the device after each).
    ///
    /// # Errors
    /// [`NetError`] for a wrong number of images or a mask of another size.
    pub fn run(
        &self,
        images: &[GrayImage],
        timed: bool,
    ) -> Result<(FrameResult, CascadeTimings), NetError> {
        let inputs = input_tensors(&self.net.config, images, &self.masks, &self.device)?;
        let (out, timings) = self.net.forward_timed(&inputs, &self.geometry, timed)?;
        let [_, _, fine] = out.stages;
        let entropy = read_values(fine.entropy(), "entropy map")?;
        let index = read_values(fine.index, "index map")?;
        let hypotheses = self.geometry.hypotheses;
        let inv_depth = index
            .iter()
            .map(|&n| hypotheses.inv_depth(f64::from(n)) as f32)
            .collect();
        let result = FrameResult {
            height: self.grid.height,
            width: self.grid.width,
            index,
            inv_depth,
            entropy,
            seconds: timings.total,
        };
        Ok((result, timings))
    }
}
