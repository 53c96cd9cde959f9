//! What the trainer needs of a network family: building it, the geometry of a rig rotation,
//! the training loss, the validation prediction and the weight files. The paper's network and
//! the cascade implement it, so one trainer (epochs, loader, checkpoints, validation) serves
//! both.

use std::path::Path;

use burn::module::Module;
use burn::tensor::{Device, Tensor};
use omnimvs_data::gt::GroundTruth;

use super::learner::{masked_l1, target_data_with};
use super::sample::{Sample, SampleSource};
use crate::cascade::geometry::crop_columns;
use crate::cascade::{CascadeGeometry, CascadeNet};
use crate::config::NetConfig;
use crate::error::NetError;
use crate::model::{OmniMvsNet, SweepTaps};
use crate::weights;

/// A network the [`super::Trainer`] can train.
pub trait Trainable: Module + Sized {
    /// What a forward pass needs about one rotation of a source's rig, on one device.
    type Geometry: Clone;

    /// A network for `config` on `device`: from `init` weights when given, else random.
    ///
    /// # Errors
    /// [`NetError`] for an invalid configuration or unreadable weights.
    fn build(config: &NetConfig, init: Option<&Path>, device: &Device) -> Result<Self, NetError>;

    /// The sizes the network was built for.
    fn config(&self) -> &NetConfig;

    /// The geometry of `source`'s rig under its rotation `rotation`, on `device`.
    ///
    /// # Errors
    /// [`NetError`] when the rig does not fit the network.
    fn geometry(
        &self,
        source: &SampleSource,
        rotation: usize,
        device: &Device,
    ) -> Result<Self::Geometry, NetError>;

    /// The training loss of a sample (`images` on the training device, camera `order` at the
    /// concatenation where the family has one).
    ///
    /// # Errors
    /// [`NetError`] for inputs that do not fit the network.
    fn loss(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        order: &[usize],
        sample: &Sample,
    ) -> Result<Tensor<1>, NetError>;

    /// The inference-mode index map `[1, H, W]` on the output grid, for validation
    /// (`geometry` of the identity rotation, on the inference device).
    ///
    /// # Errors
    /// [`NetError`] for inputs that do not fit the network.
    fn predict(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        source: &SampleSource,
    ) -> Result<Tensor<3>, NetError>;

    /// Writes the weights (safetensors) and the configuration beside them.
    ///
    /// # Errors
    /// [`NetError`] when a file cannot be written.
    fn save_weights(&self, path: &Path) -> Result<(), NetError>;
}

impl Trainable for OmniMvsNet {
    type Geometry = Vec<SweepTaps>;

    fn build(config: &NetConfig, init: Option<&Path>, device: &Device) -> Result<Self, NetError> {
        match init {
            Some(path) => weights::load_any(path, config, device),
            None => OmniMvsNet::new(config, device),
        }
    }

    fn config(&self) -> &NetConfig {
        &self.config
    }

    fn geometry(
        &self,
        source: &SampleSource,
        rotation: usize,
        device: &Device,
    ) -> Result<Self::Geometry, NetError> {
        let grids = source.grids.get(rotation).ok_or_else(|| NetError::Shape {
            what: "rotation of the augmentation".into(),
            expected: vec![source.grids.len()],
            actual: vec![rotation],
        })?;
        Ok(SweepTaps::for_grids(
            grids,
            self.config.feature_size(),
            device,
        ))
    }

    fn loss(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        order: &[usize],
        sample: &Sample,
    ) -> Result<Tensor<1>, NetError> {
        let device = first_device(images, self.config.num_cameras)?;
        let out = self.forward(images, geometry, order)?; // index [1, H, W]
        Ok(index_l1(out.index, &sample.gt, true, &device))
    }

    fn predict(
        &self,
        images: &[Tensor<4>],
        _geometry: &Self::Geometry,
        source: &SampleSource,
    ) -> Result<Tensor<3>, NetError> {
        // The host sweep of the identity rotation's tables: no device taps needed.
        let grids = source.grids.first().ok_or_else(|| NetError::Shape {
            what: "rotations of the augmentation".into(),
            expected: vec![1],
            actual: vec![0],
        })?;
        Ok(self.infer(images, grids, &self.identity_order())?.index)
    }

    fn save_weights(&self, path: &Path) -> Result<(), NetError> {
        weights::save(self, path)
    }
}

impl Trainable for CascadeNet {
    type Geometry = CascadeGeometry;

    fn build(config: &NetConfig, init: Option<&Path>, device: &Device) -> Result<Self, NetError> {
        match init {
            Some(path) => weights::load_cascade_grown(path, config, device),
            None => CascadeNet::new(config, device),
        }
    }

    fn config(&self) -> &NetConfig {
        &self.config
    }

    fn geometry(
        &self,
        source: &SampleSource,
        rotation: usize,
        device: &Device,
    ) -> Result<Self::Geometry, NetError> {
        CascadeGeometry::new(
            &source.rotated_rig(rotation),
            &self.config,
            &source.hypotheses,
            device,
        )
    }

    fn loss(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        _order: &[usize],
        sample: &Sample,
    ) -> Result<Tensor<1>, NetError> {
        let device = first_device(images, self.config.num_cameras)?;
        if sample.stage_gt.len() != 2 {
            return Err(NetError::Shape {
                what: "ground truth of the cascade's coarse and half-resolution stages".into(),
                expected: vec![2],
                actual: vec![sample.stage_gt.len()],
            });
        }
        let (out, _) = self.forward_window(images, geometry, sample.window, false, true)?;
        let (mid, fine) = match sample.window {
            Some(w) => (
                crop_gt(&sample.stage_gt[1], w.scaled(2))?,
                crop_gt(&sample.gt, w.scaled(1))?,
            ),
            None => (sample.stage_gt[1].clone(), sample.gt.clone()),
        };
        let targets = [&sample.stage_gt[0], &mid, &fine];
        let weights = self.config.cascade.loss_weights;
        let mut total: Option<Tensor<1>> = None;
        for ((stage, gt), w) in out.stages.into_iter().zip(targets).zip(weights) {
            let loss = index_l1(stage.index, gt, false, &device).mul_scalar(w);
            total = Some(match total {
                Some(t) => t + loss,
                None => loss,
            });
        }
        total.ok_or_else(|| no_images(self.config.num_cameras))
    }

    fn predict(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        _source: &SampleSource,
    ) -> Result<Tensor<3>, NetError> {
        let [_, _, fine] = self.forward(images, geometry)?.stages;
        Ok(fine.index)
    }

    fn save_weights(&self, path: &Path) -> Result<(), NetError> {
        weights::save_module(self, &self.config, path)
    }
}

/// The columns `cols` of a ground truth.
fn crop_gt(gt: &GroundTruth, cols: std::ops::Range<usize>) -> Result<GroundTruth, NetError> {
    let grid = omnimvs_sweep::EquirectGrid::new(gt.height, gt.width, 45.0)?;
    let index = crop_columns(&gt.index, &grid, &cols)?;
    let valid = gt
        .valid
        .chunks_exact(gt.width)
        .flat_map(|row| row[cols.clone()].iter().copied())
        .collect();
    Ok(GroundTruth {
        width: cols.len(),
        height: gt.height,
        index,
        valid,
    })
}

/// The device of the first image.
fn first_device(images: &[Tensor<4>], expected: usize) -> Result<Device, NetError> {
    images
        .first()
        .map(Tensor::device)
        .ok_or_else(|| no_images(expected))
}

fn no_images(expected: usize) -> NetError {
    NetError::Shape {
        what: "images per frame".into(),
        expected: vec![expected],
        actual: vec![0],
    }
}

/// Masked L1 between an index map `[1, H, W]` and the ground truth on the same grid; the
/// target is the rounded ground-truth index when `round` (the paper's network, as trained so
/// far), the exact index otherwise.
fn index_l1(index: Tensor<3>, gt: &GroundTruth, round: bool, device: &Device) -> Tensor<1> {
    let (target, mask) = target_data_with(gt, round);
    masked_l1(
        index,
        Tensor::from_data(target, device),
        Tensor::from_data(mask, device),
    )
}
