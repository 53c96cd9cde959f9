//! Training of the MC-CNN-style matching-cost network (`omnimvs_net::mccnn`) with
//! MC-CNN-fast's hinge loss on patch pairs drawn through the real rig.
//!
//! Every sample is a ground-truth pixel of the 160x640 grid and two cameras that both see its
//! 3D point: the positive pair is the two cameras' 9x9 patches (on the stride-downscaled,
//! normalised fisheye images) around the point's projections, the negative pair the same two
//! cameras' patches around the projections of the same ray on a wrong sphere, `k` hypotheses
//! away (`neg_min <= |k| <= neg_max`, as MC-CNN draws negatives a few disparities away). The
//! loss is `max(0, margin + cos(neg) - cos(pos))` (MC-CNN-fast, margin 0.2); the pair costs
//! of the cost volume are exactly these cosines, so the network learns what SGM then sees.
//!
//! The run folder holds `train_config.json`, `metrics.jsonl` (one line per `log_every` steps:
//! training and validation loss and ranking accuracy), `model.safetensors` (+ `.json`) and
//! `checkpoint/` (model, Adam state, `state.json`; written atomically every `log_every`
//! steps): `--resume` continues from the last checkpoint, the draws of every step seeded by
//! the step number, so a resumed run makes the same choices.

use std::path::{Path, PathBuf};

use burn::tensor::{Device, Tensor, TensorData, activation};
use omnimvs_core::GrayImage;
use omnimvs_core::interp::mix_2d;
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::mccnn::{self, McCnn, McCnnConfig, pool};
use serde::{Deserialize, Serialize};

use crate::cost_run::{CostModel, CostModelTrainer, Progress, Schedule, Source};
use crate::error::TrainError;
use crate::rng::SplitMix64;

/// Everything a matching-cost run needs; written to `train_config.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CostTrainConfig {
    /// Dataset folders with ground truth.
    pub data: Vec<PathBuf>,
    /// Training frames of each dataset, inclusive.
    pub train_frames: (u32, u32),
    /// Validation frames of each dataset, inclusive (outside the training frames).
    pub val_frames: (u32, u32),
    /// The network.
    pub net: McCnnConfig,
    /// Total steps.
    pub steps: usize,
    /// Sample pairs per step.
    pub batch: usize,
    /// Adam learning rate.
    pub lr: f64,
    /// Hinge margin (0.2 in MC-CNN-fast).
    pub margin: f32,
    /// Fewest hypotheses between the true and the negative sphere.
    pub neg_min: usize,
    /// Most hypotheses between them.
    pub neg_max: usize,
    /// Steps on each loaded frame before the next one.
    pub frame_every: usize,
    /// Steps between metrics lines and checkpoints.
    pub log_every: usize,
    /// Grid and hypotheses of the ground truth (`h`, `w`, `N`).
    pub grid: (usize, usize, usize),
    pub seed: u64,
}

impl Default for CostTrainConfig {
    fn default() -> Self {
        Self {
            data: Vec::new(),
            train_frames: (1, 400),
            val_frames: (1191, 1200),
            net: McCnnConfig::default(),
            steps: 2000,
            batch: 128,
            lr: 1e-3,
            margin: 0.2,
            neg_min: 2,
            neg_max: 24,
            frame_every: 4,
            log_every: 100,
            grid: (160, 640, 192),
            seed: 0,
        }
    }
}

/// One metrics line (`train_acc`, `val_acc`: the share of pairs where the true sphere matches
/// better than the wrong one).
pub use crate::cost_run::Progress as CostRecord;

/// One frame ready for drawing samples.
pub struct Frame {
    source: usize,
    /// Normalised, pooled images.
    images: Vec<GrayImage>,
    gt: GroundTruth,
}

fn load_frame(
    sources: &[Source],
    source: usize,
    frame: u32,
    stride: usize,
) -> Result<Frame, TrainError> {
    let s = &sources[source];
    let raw = s.dataset.read_frame(frame)?;
    let images = raw
        .iter()
        .zip(&s.masks)
        .map(|(img, m)| {
            Ok(pool(
                &omnimvs_data::image_io::normalize_for_network(img, Some(m))?,
                stride,
            ))
        })
        .collect::<Result<Vec<_>, TrainError>>()?;
    let gt = s
        .dataset
        .ground_truth(frame, &s.spec.grid, &s.spec.hypotheses)?
        .ok_or_else(|| TrainError::InvalidConfig {
            field: "data",
            message: format!(
                "{}: frame {frame} has no ground truth",
                s.dataset.config_path.display()
            ),
        })?;
    Ok(Frame { source, images, gt })
}

/// The `patch x patch` patch of a pooled image around full-resolution position `(col, row)`
/// (bilinear, zero outside), appended to `out`.
fn push_patch(
    img: &GrayImage,
    col: f32,
    row: f32,
    stride: usize,
    patch: usize,
    out: &mut Vec<f32>,
) {
    let s = stride as f32;
    let cx = (col - (s - 1.0) * 0.5) / s;
    let cy = (row - (s - 1.0) * 0.5) / s;
    let r = (patch / 2) as f32;
    let at = |x: isize, y: isize| -> f32 {
        if x < 0 || y < 0 || x as usize >= img.width || y as usize >= img.height {
            0.0
        } else {
            img.data[y as usize * img.width + x as usize]
        }
    };
    for dy in 0..patch {
        for dx in 0..patch {
            let (x, y) = (cx + dx as f32 - r, cy + dy as f32 - r);
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (x0, y0) = (x0 as isize, y0 as isize);
            let corners = [
                at(x0, y0),
                at(x0 + 1, y0),
                at(x0, y0 + 1),
                at(x0 + 1, y0 + 1),
            ];
            out.push(mix_2d(corners, fx, fy));
        }
    }
}

/// Where grid pixel `i` on sphere `inv_depth` lands in camera `cam`, if its mask sees it.
fn seen(src: &Source, cam: usize, i: usize, inv_depth: f32) -> Option<(f32, f32)> {
    let (c, r) = src.projectors[cam].project(i, inv_depth)?;
    let m = &src.masks[cam];
    let (x, y) = (c.round(), r.round());
    if x < 4.0 || y < 4.0 || x >= m.width as f32 - 4.0 || y >= m.height as f32 - 4.0 {
        return None;
    }
    m.valid[y as usize * m.width as usize + x as usize].then_some((c, r))
}

/// `batch` samples of a frame: `[4 batch, 1, p, p]` patches in the order positive A,
/// positive B, negative A, negative B (each `batch` long).
fn draw_batch(
    sources: &[Source],
    frame: &Frame,
    config: &CostTrainConfig,
    rng: &mut SplitMix64,
) -> Vec<f32> {
    let src = &sources[frame.source];
    let hyps = &src.spec.hypotheses;
    let ncam = src.projectors.len();
    let (p, stride) = (config.net.patch(), config.net.stride);
    let mut parts: [Vec<f32>; 4] = Default::default();
    let npix = frame.gt.index.len();
    let mut done = 0;
    let mut tries = 0;
    while done < config.batch && tries < config.batch * 200 {
        tries += 1;
        let i = rng.below(npix);
        let n_true = frame.gt.index[i];
        // Sky (index 0) has no texture to match.
        if !frame.gt.valid[i] || n_true < 0.5 {
            continue;
        }
        let (a, b) = {
            let a = rng.below(ncam);
            let b = (a + 1 + rng.below(ncam - 1)) % ncam;
            (a, b)
        };
        let k = config.neg_min + rng.below(config.neg_max - config.neg_min + 1);
        let sign = if rng.below(2) == 0 { -1.0 } else { 1.0 };
        let n_neg = n_true + sign * k as f32;
        let n_neg = if (0.0..=(hyps.count - 1) as f32).contains(&n_neg) {
            n_neg
        } else {
            n_true - sign * k as f32
        };
        let d_true = hyps.inv_depth(f64::from(n_true)) as f32;
        let d_neg = hyps.inv_depth(f64::from(n_neg)) as f32;
        let (Some(pa), Some(pb), Some(na), Some(nb)) = (
            seen(src, a, i, d_true),
            seen(src, b, i, d_true),
            seen(src, a, i, d_neg),
            seen(src, b, i, d_neg),
        ) else {
            continue;
        };
        for (part, (cam, (c, r))) in parts.iter_mut().zip([(a, pa), (b, pb), (a, na), (b, nb)]) {
            push_patch(&frame.images[cam], c, r, stride, p, part);
        }
        done += 1;
    }
    parts.concat()
}

/// Hinge loss and ranking accuracy of a batch of `4 b` patches (positive A, positive B,
/// negative A, negative B, `b` each).
pub fn batch_loss(
    net: &McCnn,
    patches: Vec<f32>,
    margin: f32,
    device: &Device,
) -> (Tensor<1>, f32) {
    let p = net.config.patch();
    let b4 = patches.len() / (p * p);
    let b = b4 / 4;
    let x = Tensor::<4>::from_data(TensorData::new(patches, [b4, 1, p, p]), device);
    let d = net.describe(x);
    let pa = d.clone().narrow(0, 0, b);
    let pb = d.clone().narrow(0, b, b);
    let na = d.clone().narrow(0, 2 * b, b);
    let nb = d.narrow(0, 3 * b, b);
    let cos_pos = (pa * pb).sum_dim(1);
    let cos_neg = (na * nb).sum_dim(1);
    let diff = cos_neg - cos_pos;
    let acc = diff
        .clone()
        .lower_elem(0.0)
        .float()
        .mean()
        .into_scalar::<f32>();
    let loss = activation::relu(diff.add_scalar(margin)).mean();
    (loss, acc)
}

/// A matching-cost training run of the MC-CNN-style network.
pub type CostTrainer = CostModelTrainer<CostTrainConfig>;

impl CostModel for CostTrainConfig {
    type Net = McCnn;
    type Frame = Frame;
    /// `[4 batch, 1, p, p]` patches: positive A, positive B, negative A, negative B.
    type Batch = Vec<f32>;
    type Record = CostRecord;

    fn data(&self) -> &[PathBuf] {
        &self.data
    }

    fn grid(&self) -> (usize, usize, usize) {
        self.grid
    }

    fn val_frames(&self) -> (u32, u32) {
        self.val_frames
    }

    fn schedule(&self) -> Schedule {
        Schedule {
            seed: self.seed,
            steps: self.steps,
            frame_every: self.frame_every,
            train_frames: self.train_frames,
            log_every: self.log_every,
            lr: self.lr,
        }
    }

    fn set_steps(&mut self, steps: usize) {
        self.steps = steps;
    }

    fn check(&self) -> Result<(), TrainError> {
        if self.batch == 0 || self.neg_max < self.neg_min || self.frame_every == 0 {
            return Err(TrainError::InvalidConfig {
                field: "batch",
                message: "expected batch > 0, neg_max >= neg_min, frame_every > 0".into(),
            });
        }
        Ok(())
    }

    fn build(&self, device: &Device) -> Result<McCnn, TrainError> {
        Ok(McCnn::new(&self.net, device)?)
    }

    fn load_frame(
        &self,
        sources: &[Source],
        source: usize,
        frame: u32,
    ) -> Result<Frame, TrainError> {
        load_frame(sources, source, frame, self.net.stride)
    }

    fn draw(&self, sources: &[Source], frame: &Frame, rng: &mut SplitMix64) -> Option<Vec<f32>> {
        let patches = draw_batch(sources, frame, self, rng);
        (!patches.is_empty()).then_some(patches)
    }

    /// One batch per frame, empty or not.
    fn validation_batches(
        &self,
        sources: &[Source],
        frame: &Frame,
        source: usize,
        j: usize,
    ) -> Vec<Vec<f32>> {
        let mut rng = SplitMix64::new(0x5EED ^ (source as u64 * 31 + j as u64));
        vec![draw_batch(sources, frame, self, &mut rng)]
    }

    fn loss(&self, net: &McCnn, patches: &Vec<f32>, device: &Device) -> (Tensor<1>, f32) {
        batch_loss(net, patches.clone(), self.margin, device)
    }

    fn record(&self, progress: &Progress, _val: &[Vec<f32>]) -> CostRecord {
        progress.clone()
    }

    fn save(net: &McCnn, path: &Path) -> Result<(), TrainError> {
        Ok(mccnn::save(net, path)?)
    }
}
