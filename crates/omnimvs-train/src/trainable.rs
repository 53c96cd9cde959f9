//! What the trainer needs of a network family: building it, the geometry of a rig rotation,
//! the training loss, the validation prediction and the weight files. The paper's network and
//! the cascade implement it, so one trainer (epochs, loader, checkpoints, validation) serves
//! both.

use std::path::Path;

use burn::module::Module;
use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_data::gt::GroundTruth;

use crate::error::TrainError;
use crate::learner::{masked_l1, target_data_with};
use crate::sample::{Sample, SampleSource};
use omnimvs_net::cascade::geometry::crop_columns;
use omnimvs_net::cascade::sampler::coarse_indices;
use omnimvs_net::cascade::{CascadeGeometry, CascadeNet};
use omnimvs_net::config::NetConfig;
use omnimvs_net::model::{OmniMvsNet, SweepTaps};
use omnimvs_net::weights;

/// A network the [`crate::Trainer`] can train.
pub trait Trainable: Module + Sized {
    /// What a forward pass needs about one rotation of a source's rig, on one device.
    type Geometry: Clone;

    /// A network for `config` on `device`: from `init` weights when given, else random.
    ///
    /// # Errors
    /// [`TrainError`] for an invalid configuration or unreadable weights.
    fn build(config: &NetConfig, init: Option<&Path>, device: &Device) -> Result<Self, TrainError>;

    /// The sizes the network was built for.
    fn config(&self) -> &NetConfig;

    /// The geometry of `source`'s rig under its rotation `rotation`, on `device`.
    ///
    /// # Errors
    /// [`TrainError`] when the rig does not fit the network.
    fn geometry(
        &self,
        source: &SampleSource,
        rotation: usize,
        device: &Device,
    ) -> Result<Self::Geometry, TrainError>;

    /// The training loss of a sample (`images` on the training device, camera `order` at the
    /// concatenation where the family has one).
    ///
    /// # Errors
    /// [`TrainError`] for inputs that do not fit the network.
    fn loss(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        order: &[usize],
        sample: &Sample,
    ) -> Result<Tensor<1>, TrainError>;

    /// The inference-mode index map `[1, H, W]` on the output grid, for validation
    /// (`geometry` of the identity rotation, on the inference device).
    ///
    /// # Errors
    /// [`TrainError`] for inputs that do not fit the network.
    fn predict(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        source: &SampleSource,
    ) -> Result<Tensor<3>, TrainError>;

    /// Writes the weights (safetensors) and the configuration beside them.
    ///
    /// # Errors
    /// [`TrainError`] when a file cannot be written.
    fn save_weights(&self, path: &Path) -> Result<(), TrainError>;
}

impl Trainable for OmniMvsNet {
    type Geometry = Vec<SweepTaps>;

    fn build(config: &NetConfig, init: Option<&Path>, device: &Device) -> Result<Self, TrainError> {
        Ok(match init {
            Some(path) => weights::load_any(path, config, device)?,
            None => OmniMvsNet::new(config, device)?,
        })
    }

    fn config(&self) -> &NetConfig {
        &self.config
    }

    fn geometry(
        &self,
        source: &SampleSource,
        rotation: usize,
        device: &Device,
    ) -> Result<Self::Geometry, TrainError> {
        let grids = source
            .grids
            .get(rotation)
            .ok_or_else(|| TrainError::Shape {
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
    ) -> Result<Tensor<1>, TrainError> {
        let device = first_device(images, self.config.num_cameras)?;
        let out = self.forward(images, geometry, order)?; // index [1, H, W]
        Ok(index_l1(out.index, &sample.gt, true, &device))
    }

    fn predict(
        &self,
        images: &[Tensor<4>],
        _geometry: &Self::Geometry,
        source: &SampleSource,
    ) -> Result<Tensor<3>, TrainError> {
        // The host sweep of the identity rotation's tables: no device taps needed.
        let grids = source.grids.first().ok_or_else(|| TrainError::Shape {
            what: "rotations of the augmentation".into(),
            expected: vec![1],
            actual: vec![0],
        })?;
        Ok(self.infer(images, grids, &self.identity_order())?.index)
    }

    fn save_weights(&self, path: &Path) -> Result<(), TrainError> {
        Ok(weights::save(self, path)?)
    }
}

impl Trainable for CascadeNet {
    type Geometry = CascadeGeometry;

    fn build(config: &NetConfig, init: Option<&Path>, device: &Device) -> Result<Self, TrainError> {
        Ok(match init {
            Some(path) => weights::load_cascade_grown(path, config, device)?,
            None => CascadeNet::new(config, device)?,
        })
    }

    fn config(&self) -> &NetConfig {
        &self.config
    }

    fn geometry(
        &self,
        source: &SampleSource,
        rotation: usize,
        device: &Device,
    ) -> Result<Self::Geometry, TrainError> {
        Ok(CascadeGeometry::new(
            &source.rotated_rig(rotation),
            &self.config,
            &source.hypotheses,
            device,
        )?)
    }

    fn loss(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        _order: &[usize],
        sample: &Sample,
    ) -> Result<Tensor<1>, TrainError> {
        let device = first_device(images, self.config.num_cameras)?;
        if sample.stage_gt.len() != 2 {
            return Err(TrainError::Shape {
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
        let distribution_weight = self.config.cascade.coarse_distribution_weight;
        let mut total: Option<Tensor<1>> = (distribution_weight > 0.0).then(|| {
            let spheres =
                coarse_indices(self.config.cascade.coarse_spheres, self.config.num_invdepth);
            distribution_ce(
                out.stages[0].prob.clone(),
                &sample.stage_gt[0],
                &spheres,
                &device,
            )
            .mul_scalar(distribution_weight)
        });
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
    ) -> Result<Tensor<3>, TrainError> {
        let [_, _, fine] = self.forward(images, geometry)?.stages;
        Ok(fine.index)
    }

    fn save_weights(&self, path: &Path) -> Result<(), TrainError> {
        Ok(weights::save_module(self, &self.config, path)?)
    }
}

/// Laplacian target distributions over `spheres` (fractional indices, `N` units, evenly
/// spaced) around each pixel's exact ground-truth index, scale half the spacing:
/// `[1, K, H, W]` data (zero at invalid pixels) and the valid mask `[1, 1, H, W]`.
pub fn distribution_target(gt: &GroundTruth, spheres: &[f64]) -> (TensorData, TensorData) {
    let (k, plane) = (spheres.len(), gt.width * gt.height);
    let spacing = match spheres {
        [first, .., last] => (last - first) / (k - 1) as f64,
        _ => 1.0,
    };
    let scale = (spacing / 2.0).max(f64::EPSILON);
    let mut target = vec![0f32; k * plane];
    let mut weights = vec![0f64; k];
    for (i, (&n, &valid)) in gt.index.iter().zip(&gt.valid).enumerate() {
        if !valid {
            continue;
        }
        for (w, &c) in weights.iter_mut().zip(spheres) {
            *w = (-(c - f64::from(n)).abs() / scale).exp();
        }
        let sum: f64 = weights.iter().sum();
        for (j, w) in weights.iter().enumerate() {
            target[j * plane + i] = (w / sum) as f32;
        }
    }
    let mask = gt.valid.iter().map(|&v| f32::from(u8::from(v))).collect();
    (
        TensorData::new(target, [1, k, gt.height, gt.width]),
        TensorData::new(mask, [1, 1, gt.height, gt.width]),
    )
}

/// Mean cross-entropy, over the valid pixels of `gt`, between [`distribution_target`] and a
/// stage's distribution `prob` `[1, K, H, W]` over `spheres`.
pub fn distribution_ce(
    prob: Tensor<4>,
    gt: &GroundTruth,
    spheres: &[f64],
    device: &Device,
) -> Tensor<1> {
    let (target, mask) = distribution_target(gt, spheres);
    let target = Tensor::<4>::from_data(target, device);
    let mask = Tensor::<4>::from_data(mask, device);
    let count = mask.clone().sum().clamp_min(1.0); // [1]
    let ce = (target * prob.clamp_min(1e-6).log()).sum_dim(1).neg(); // [1, 1, H, W]
    (ce * mask).sum() / count
}

/// The columns `cols` of a ground truth.
fn crop_gt(gt: &GroundTruth, cols: std::ops::Range<usize>) -> Result<GroundTruth, TrainError> {
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
fn first_device(images: &[Tensor<4>], expected: usize) -> Result<Device, TrainError> {
    images
        .first()
        .map(Tensor::device)
        .ok_or_else(|| no_images(expected))
}

fn no_images(expected: usize) -> TrainError {
    TrainError::Shape {
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Two valid pixels (indices 12.0 and 30.5) and an invalid one, on 5 spheres 0, 10.. 40.
    fn three_pixels() -> (GroundTruth, Vec<f64>) {
        let gt = GroundTruth {
            width: 3,
            height: 1,
            index: vec![12.0, 30.5, 7.0],
            valid: vec![true, true, false],
        };
        (gt, vec![0.0, 10.0, 20.0, 30.0, 40.0])
    }

    #[test]
    fn distribution_targets_peak_at_the_truth_and_sum_to_one() {
        let (gt, spheres) = three_pixels();
        let (target, mask) = distribution_target(&gt, &spheres);
        let t = target.try_to_vec::<f32>().unwrap();
        let at = |k: usize, i: usize| t[k * 3 + i];
        for i in 0..2 {
            let sum: f32 = (0..5).map(|k| at(k, i)).sum();
            assert!((sum - 1.0).abs() < 1e-5, "pixel {i} sums to {sum}");
        }
        // Pixel 0 (12.0) peaks at sphere 10, then 20; pixel 1 (30.5) at 30, then 40.
        assert!(at(1, 0) > at(2, 0) && at(2, 0) > at(0, 0) && at(0, 0) > at(4, 0));
        assert!(at(3, 1) > at(4, 1) && at(4, 1) > at(2, 1));
        // Laplacian of scale 5 (half the spacing): neighbours 2 and 8 units away.
        let ratio = at(1, 0) / at(2, 0);
        assert!((ratio - (6.0f32 / 5.0).exp()).abs() < 1e-3, "ratio {ratio}");
        assert!((0..5).all(|k| at(k, 2) == 0.0));
        assert_eq!(mask.try_to_vec::<f32>().unwrap(), vec![1.0, 1.0, 0.0]);
    }

    #[test]
    fn the_cross_entropy_prefers_a_peak_at_the_truth() {
        let (gt, spheres) = three_pixels();
        let device = Device::flex();
        let prob = |per_pixel: [[f32; 5]; 3]| {
            // [1, K, 1, 3] from per-pixel distributions.
            let data: Vec<f32> = (0..5)
                .flat_map(|k| per_pixel.iter().map(move |p| p[k]))
                .collect();
            Tensor::<4>::from_data(TensorData::new(data, [1, 5, 1, 3]), &device)
        };
        let ce = |p| {
            distribution_ce(prob(p), &gt, &spheres, &device)
                .into_data()
                .try_to_vec::<f32>()
                .unwrap()[0]
        };
        let flat = [0.2; 5];
        let right = [
            [0.05, 0.8, 0.1, 0.03, 0.02],
            [0.02, 0.03, 0.1, 0.75, 0.1],
            flat,
        ];
        let wrong = [
            [0.02, 0.03, 0.1, 0.05, 0.8],
            [0.8, 0.1, 0.05, 0.03, 0.02],
            flat,
        ];
        let (r, f, w) = (ce(right), ce([flat; 3]), ce(wrong));
        assert!(r < f && f < w, "right {r}, flat {f}, wrong {w}");
        // The invalid pixel does not count: changing it changes nothing.
        let mut other = right;
        other[2] = [0.96, 0.01, 0.01, 0.01, 0.01];
        assert!((ce(other) - r).abs() < 1e-6);
    }
}
