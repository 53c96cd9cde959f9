//! What the trainer needs of a network family: building it, the geometry of a rig rotation,
//! the training loss, the validation prediction and the weight files. The paper's network and
//! the cascade implement it, so one trainer (epochs, loader, checkpoints, validation) serves
//! both.

use std::path::Path;

use burn::module::Module;
use burn::tensor::activation::softmax;
use burn::tensor::{Device, Tensor};
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::cascade::geometry::crop_columns;
use omnimvs_net::cascade::model::{CascadeFeatures, StageOutput};
use omnimvs_net::cascade::sampler::coarse_spacing;
use omnimvs_net::cascade::{CascadeGeometry, CascadeNet};
use omnimvs_net::config::NetConfig;
use omnimvs_net::model::{OmniMvsNet, SweepTaps};
use omnimvs_net::weights;

use crate::config::TrainParts;
use crate::error::TrainError;
use crate::loss::{masked_l1, target_data_with};
use crate::sample::{Sample, SampleSource};

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
    /// concatenation where the family has one) when the run trains `parts` (a family may
    /// leave out the terms of frozen parts, and the forward pass they alone need).
    ///
    /// # Errors
    /// [`TrainError`] for inputs that do not fit the network.
    fn loss(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        order: &[usize],
        sample: &Sample,
        parts: TrainParts,
    ) -> Result<Tensor<1>, TrainError>;

    /// The inference network (from [`crate::Learner::inference_net`]) on the family's host
    /// path for a CPU backend, as `omnimvs infer` runs it there: the same answers to float
    /// rounding, in less time. The default: the network as it is.
    #[must_use]
    fn on_host(self) -> Self {
        self
    }

    /// The geometry of `source`'s rig (identity rotation) for validation on `device`, on the
    /// family's host path when `host` ([`Trainable::on_host`]). The default: [`Trainable::geometry`].
    ///
    /// # Errors
    /// [`TrainError`] when the rig does not fit the network.
    fn validation_geometry(
        &self,
        source: &SampleSource,
        device: &Device,
        host: bool,
    ) -> Result<Self::Geometry, TrainError> {
        let _ = host;
        self.geometry(source, 0, device)
    }

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

    /// The network with every weight outside `parts` frozen (no gradient).
    ///
    /// # Errors
    /// [`TrainError::InvalidConfig`] when the network has no such parts.
    fn train_only(self, parts: TrainParts) -> Result<Self, TrainError> {
        match parts {
            TrainParts::All => Ok(self),
            TrainParts::Upsampling => Err(no_upsampling()),
            TrainParts::Coarse | TrainParts::Mid | TrainParts::Fine => {
                Err(TrainError::InvalidConfig {
                    field: "train_only",
                    message:
                        "`coarse`, `mid` and `fine` train a stage of the cascade; this network \
                          is not a cascade"
                            .into(),
                })
            }
        }
    }
}

fn no_upsampling() -> TrainError {
    TrainError::InvalidConfig {
        field: "train_only",
        message: "`upsampling` trains the cascade's learnt upsampling selectors, which this \
                  network has not (`convex_upsampling`)"
            .into(),
    }
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
        _parts: TrainParts,
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

    fn on_host(self) -> Self {
        self.fold_batch_norm().with_host_convs()
    }

    fn validation_geometry(
        &self,
        source: &SampleSource,
        device: &Device,
        host: bool,
    ) -> Result<Self::Geometry, TrainError> {
        Ok(CascadeGeometry::with_host_correlation(
            &source.rotated_rig(0),
            &self.config,
            &source.hypotheses,
            device,
            host,
        )?)
    }

    fn loss(
        &self,
        images: &[Tensor<4>],
        geometry: &Self::Geometry,
        _order: &[usize],
        sample: &Sample,
        parts: TrainParts,
    ) -> Result<Tensor<1>, TrainError> {
        let device = first_device(images, self.config.num_cameras)?;
        if sample.stage_gt.len() != 2 {
            return Err(TrainError::Shape {
                what: "ground truth of the cascade's coarse and half-resolution stages".into(),
                expected: vec![2],
                actual: vec![sample.stage_gt.len()],
            });
        }
        let p = &self.config.cascade;
        if parts == TrainParts::Coarse {
            // The coarse stage's own terms: nothing after it has a weight that learns.
            let coarse = self.forward_coarse(images, geometry, true)?;
            let (target, mask) =
                target_tensors(&sample.stage_gt[0], false, p.sky_loss_weight, &device);
            let [terms, ..] = stage_terms(&self.config);
            return Ok(stage_loss(coarse, target, mask, terms));
        }
        let (out, _) = self.forward_window(images, geometry, sample.window, false, true)?;
        let (mid, fine) = match sample.window {
            Some(w) => (
                crop_gt(&sample.stage_gt[1], w.scaled(2))?,
                crop_gt(&sample.gt, w.scaled(1))?,
            ),
            None => (sample.stage_gt[1].clone(), sample.gt.clone()),
        };
        // Every stage's truth and loss weights as tensors, once.
        let targets = [&sample.stage_gt[0], &mid, &fine]
            .map(|gt| target_tensors(gt, false, p.sky_loss_weight, &device));
        let mut losses = Vec::new();
        // The learnt upsampling's centres, each against the truth of the grid it feeds.
        for ((up, (target, mask)), w) in out
            .upsampled
            .iter()
            .zip(&targets[1..])
            .zip(&p.loss_weights[1..])
        {
            if let Some(up) = up {
                losses.push(masked_l1(up.clone(), target.clone(), mask.clone()).mul_scalar(*w));
            }
        }
        for ((stage, (target, mask)), terms) in out
            .stages
            .into_iter()
            .zip(targets)
            .zip(stage_terms(&self.config))
        {
            losses.push(stage_loss(stage, target, mask, terms));
        }
        losses
            .into_iter()
            .reduce(|total, loss| total + loss)
            .ok_or_else(|| no_images(self.config.num_cameras))
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

    fn train_only(mut self, parts: TrainParts) -> Result<Self, TrainError> {
        match parts {
            TrainParts::All => Ok(self),
            TrainParts::Upsampling => {
                // The selectors the network has: both grids', or the half grid's alone
                // (`convex_upsampling_full: false`, the bundled model's).
                if self.up_mid.is_none() && self.up_fine.is_none() {
                    return Err(no_upsampling());
                }
                self.features = self.features.no_grad();
                self.coarse = self.coarse.no_grad();
                self.mid = self.mid.no_grad();
                self.fine = self.fine.no_grad();
                Ok(self)
            }
            TrainParts::Coarse => {
                let f = self.features;
                self.features = CascadeFeatures {
                    conv0: f.conv0.no_grad(),
                    conv2: f.conv2.no_grad(),
                    out2: f.out2.no_grad(),
                    down4: f.down4.no_grad(),
                    res4: f.res4.no_grad(),
                    out4: f.out4.no_grad(),
                    ..f
                };
                self.mid = self.mid.no_grad();
                self.fine = self.fine.no_grad();
                self.up_mid = self.up_mid.no_grad();
                self.up_fine = self.up_fine.no_grad();
                Ok(self)
            }
            TrainParts::Mid => {
                self.features = self.features.no_grad();
                self.coarse = self.coarse.no_grad();
                self.fine = self.fine.no_grad();
                self.up_mid = self.up_mid.no_grad();
                self.up_fine = self.up_fine.no_grad();
                Ok(self)
            }
            TrainParts::Fine => {
                // The stride-2 projection feeds the full stage alone (and the full grid's
                // selector, frozen here, when the network has one).
                let f = self.features;
                self.features = CascadeFeatures {
                    conv0: f.conv0.no_grad(),
                    conv2: f.conv2.no_grad(),
                    down4: f.down4.no_grad(),
                    res4: f.res4.no_grad(),
                    out4: f.out4.no_grad(),
                    down8: f.down8.no_grad(),
                    res8: f.res8.no_grad(),
                    ctx8: f.ctx8.no_grad(),
                    out8: f.out8.no_grad(),
                    ..f
                };
                self.coarse = self.coarse.no_grad();
                self.mid = self.mid.no_grad();
                self.up_mid = self.up_mid.no_grad();
                self.up_fine = self.up_fine.no_grad();
                Ok(self)
            }
        }
    }
}

/// What one stage's loss weighs: its L1 (`weight`), its distribution's cross-entropy
/// (`distribution_weight`, none at 0) and the spacing of its hypotheses (`spacing`, `N` units;
/// the cross-entropy's Laplacian has half of it as its scale).
#[derive(Clone, Copy, Debug)]
struct StageTerms {
    weight: f64,
    distribution_weight: f64,
    spacing: f64,
}

/// The loss terms of the cascade's coarse, half- and full-resolution stages, in that order.
fn stage_terms(config: &NetConfig) -> [StageTerms; 3] {
    let p = &config.cascade;
    let spacings = [
        coarse_spacing(p.coarse_spheres, config.num_invdepth),
        p.stage_intervals[0],
        p.stage_intervals[1],
    ];
    let distribution_weights = [
        p.coarse_distribution_weight,
        p.refine_distribution_weight,
        p.refine_distribution_weight,
    ];
    std::array::from_fn(|i| StageTerms {
        weight: p.loss_weights[i],
        distribution_weight: distribution_weights[i],
        spacing: spacings[i],
    })
}

/// One stage's loss: the L1 of its index against `target` (weighted by `mask`) times
/// `terms.weight`, plus, when `terms.distribution_weight` is positive, that times the
/// cross-entropy of its distribution against a Laplacian of half `terms.spacing` around the
/// truth.
fn stage_loss(
    stage: StageOutput,
    target: Tensor<3>,
    mask: Tensor<3>,
    terms: StageTerms,
) -> Tensor<1> {
    let loss = masked_l1(stage.index, target.clone(), mask.clone()).mul_scalar(terms.weight);
    if terms.distribution_weight > 0.0 {
        let scale = terms.spacing / 2.0;
        let ce = distribution_ce(stage.prob, stage.hypotheses, target, mask, scale);
        loss + ce.mul_scalar(terms.distribution_weight)
    } else {
        loss
    }
}

/// Mean cross-entropy, over the pixels of `mask`, between a stage's distribution `prob` over
/// its hypotheses `hypotheses` (both `[1, K, H, W]`, hypotheses in `N` units) and a Laplacian
/// of `scale` around each pixel's exact ground-truth index `target` (`[1, H, W]`, with `mask`
/// as `target_tensors` makes them): it asks for one peak at the truth, where the L1 of the
/// mean is content with any spread whose mean is right (AcfNet's unimodal supervision). Where
/// the truth lies outside the hypotheses, the target piles on the nearest one. The target
/// carries no gradient.
pub fn distribution_ce(
    prob: Tensor<4>,
    hypotheses: Tensor<4>,
    target: Tensor<3>,
    mask: Tensor<3>,
    scale: f64,
) -> Tensor<1> {
    let index = target.unsqueeze_dim::<4>(1); // [1, 1, H, W]
    let mask = mask.unsqueeze_dim::<4>(1); // [1, 1, H, W]
    let distance = (hypotheses - index)
        .abs()
        .div_scalar(scale.max(f64::EPSILON));
    let target = softmax(distance.neg(), 1); // [1, K, H, W]
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
    let (target, mask) = target_tensors(gt, round, 1.0, device);
    masked_l1(index, target, mask)
}

/// The ground-truth indices (rounded when `round`) and the per-pixel loss weights of `gt`
/// (`sky_weight` for sky, see [`target_data_with`]) as `[1, H, W]` tensors on `device`.
/// [`masked_l1`] and [`distribution_ce`] divide by the weights' sum, so they are weighted
/// means.
fn target_tensors(
    gt: &GroundTruth,
    round: bool,
    sky_weight: f64,
    device: &Device,
) -> (Tensor<3>, Tensor<3>) {
    let (target, weights) = target_data_with(gt, round, sky_weight);
    (
        Tensor::from_data(target, device),
        Tensor::from_data(weights, device),
    )
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use burn::tensor::TensorData;

    /// Two valid pixels (indices 12.0 and 30.5) and an invalid one.
    fn three_pixels() -> GroundTruth {
        GroundTruth {
            width: 3,
            height: 1,
            index: vec![12.0, 30.5, 7.0],
            valid: vec![true, true, false],
        }
    }

    /// `[1, K, 1, 3]` from per-pixel values over `K = 5`.
    fn per_pixel(values: [[f32; 5]; 3], device: &Device) -> Tensor<4> {
        let data: Vec<f32> = (0..5)
            .flat_map(|k| values.iter().map(move |p| p[k]))
            .collect();
        Tensor::<4>::from_data(TensorData::new(data, [1, 5, 1, 3]), device)
    }

    fn ce(prob: [[f32; 5]; 3], hypotheses: [[f32; 5]; 3], scale: f64) -> f32 {
        let device = Device::flex();
        let (target, mask) = target_tensors(&three_pixels(), false, 1.0, &device);
        let loss = distribution_ce(
            per_pixel(prob, &device),
            per_pixel(hypotheses, &device),
            target,
            mask,
            scale,
        );
        loss.into_data().try_to_vec::<f32>().unwrap()[0]
    }

    const SPHERES: [[f32; 5]; 3] = [[0.0, 10.0, 20.0, 30.0, 40.0]; 3];

    #[test]
    fn the_cross_entropy_is_least_at_the_laplacian_around_the_truth() {
        // The target itself: a Laplacian of scale 5 over the spheres, normalised.
        let laplacian = |truth: f32| {
            let w: Vec<f32> = SPHERES[0]
                .iter()
                .map(|&c| (-(c - truth).abs() / 5.0).exp())
                .collect();
            let sum: f32 = w.iter().sum();
            std::array::from_fn(|k| w[k] / sum)
        };
        let flat = [0.2; 5];
        let target = [laplacian(12.0), laplacian(30.5), flat];
        let at_target = ce(target, SPHERES, 5.0);
        // Cross-entropy is the target's entropy there and more anywhere else.
        let entropy = |p: &[f32; 5]| -p.iter().map(|x| x * x.ln()).sum::<f32>();
        let expected = (entropy(&target[0]) + entropy(&target[1])) / 2.0;
        assert!(
            (at_target - expected).abs() < 1e-4,
            "{at_target} vs {expected}"
        );
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
        let (r, f, w) = (
            ce(right, SPHERES, 5.0),
            ce([flat; 3], SPHERES, 5.0),
            ce(wrong, SPHERES, 5.0),
        );
        assert!(
            at_target < r && r < f && f < w,
            "target {at_target}, right {r}, flat {f}, wrong {w}"
        );
        // The invalid pixel does not count: changing it changes nothing.
        let mut other = right;
        other[2] = [0.96, 0.01, 0.01, 0.01, 0.01];
        assert!((ce(other, SPHERES, 5.0) - r).abs() < 1e-6);
    }

    #[test]
    fn sky_pixels_weigh_as_asked_in_the_stage_losses() {
        let device = Device::flex();
        // Sky (index 0), a near pixel (index 150.5) and an invalid one.
        let gt = GroundTruth {
            width: 3,
            height: 1,
            index: vec![0.0, 150.5, 0.0],
            valid: vec![true, true, false],
        };
        let l1 = |answer: [f32; 3], sky_weight: f64| {
            let (target, weights) = target_tensors(&gt, false, sky_weight, &device);
            let index =
                Tensor::<3>::from_data(TensorData::new(answer.to_vec(), [1, 1, 3]), &device);
            masked_l1(index, target, weights)
                .into_data()
                .try_to_vec::<f32>()
                .unwrap()[0]
        };
        let (target, weights) = target_tensors(&gt, false, 0.25, &device);
        assert_eq!(
            target.into_data().try_to_vec::<f32>().unwrap(),
            vec![0.0, 150.5, 0.0]
        );
        assert_eq!(
            weights.into_data().try_to_vec::<f32>().unwrap(),
            vec![0.25, 1.0, 0.0]
        );
        // Sky 10 off and the near pixel 2 off: a weighted mean, the invalid pixel not counted.
        let answer = [10.0, 148.5, 99.0];
        assert!((l1(answer, 1.0) - 6.0).abs() < 1e-5);
        assert!((l1(answer, 0.25) - (0.25 * 10.0 + 2.0) / 1.25).abs() < 1e-5);
        // Weight 0: sky does not count at all.
        assert!((l1(answer, 0.0) - 2.0).abs() < 1e-5);
        assert!((l1([50.0, 148.5, 0.0], 0.0) - 2.0).abs() < 1e-5);
    }

    #[test]
    fn per_pixel_hypotheses_outside_the_truth_pile_the_target_on_the_nearest() {
        // Pixel 0's hypotheses 20..28 all lie above its truth 12: the target is heaviest on
        // 20, so a distribution peaked there beats one peaked at 28.
        let mut hypotheses = SPHERES;
        hypotheses[0] = [20.0, 22.0, 24.0, 26.0, 28.0];
        let flat = [0.2; 5];
        let low = [
            [0.9, 0.04, 0.03, 0.02, 0.01],
            [0.02, 0.03, 0.1, 0.75, 0.1],
            flat,
        ];
        let high = [
            [0.01, 0.02, 0.03, 0.04, 0.9],
            [0.02, 0.03, 0.1, 0.75, 0.1],
            flat,
        ];
        assert!(ce(low, hypotheses, 1.0) < ce(high, hypotheses, 1.0));
    }
}
