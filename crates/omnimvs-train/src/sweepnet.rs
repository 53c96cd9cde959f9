//! Training of the SweepNet-style matching cost (`omnimvs_net::sweepnet`).
//!
//! A sample is one ground-truth pixel of the 160x640 grid with the window features of the
//! warped images on every one of the `N` spheres (`omnimvs_stereo::sweepnet::band_features`,
//! exactly what inference computes). The loss asks the costs along the sweep to pick the true
//! sphere: a softmin over the `N` costs (`softmax(-T cost)`, `T` the configuration's
//! temperature) scored by cross-entropy against the ground-truth index, split linearly
//! between its two neighbouring spheres. Sky pixels (index below 0.5) are not drawn. Every
//! step draws `batch` pixels from one band of `band_rows` grid rows of one frame.
//!
//! The run folder holds `train_config.json`, `metrics.jsonl` (training and validation loss,
//! the share of pixels whose lowest cost is within one hypothesis of the truth, and that share
//! for the plain ZNCC cost on the same validation pixels), `model.safetensors` (+ `.json`) and
//! `checkpoint/`; `--resume` continues from the last checkpoint, every draw seeded by the step.

use std::path::{Path, PathBuf};

use burn::tensor::{Device, Tensor, TensorData, activation};
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::sweepnet::{self, SweepNet, SweepNetConfig};
use omnimvs_stereo::CameraView;
use omnimvs_stereo::sweepnet::{BandScratch, FeatureLayout, band_features};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cost_run::{CostModel, CostModelTrainer, Progress, Schedule, Source};
use crate::error::TrainError;
use crate::rng::SplitMix64;

/// Everything a SweepNet run needs; written to `train_config.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepTrainConfig {
    /// Dataset folders with ground truth.
    pub data: Vec<PathBuf>,
    /// Training frames of each dataset, inclusive.
    pub train_frames: (u32, u32),
    /// Validation frames of each dataset, inclusive (outside the training frames).
    pub val_frames: (u32, u32),
    /// The network.
    pub net: SweepNetConfig,
    /// Total steps.
    pub steps: usize,
    /// Pixels per step (each with all `N` spheres).
    pub batch: usize,
    /// Grid rows of the band a step draws its pixels from.
    pub band_rows: usize,
    /// Adam learning rate.
    pub lr: f64,
    /// Steps on each loaded frame before the next one.
    pub frame_every: usize,
    /// Steps between metrics lines and checkpoints.
    pub log_every: usize,
    /// Grid and hypotheses of the ground truth (`h`, `w`, `N`).
    pub grid: (usize, usize, usize),
    pub seed: u64,
}

impl Default for SweepTrainConfig {
    fn default() -> Self {
        Self {
            data: Vec::new(),
            train_frames: (1, 400),
            val_frames: (1191, 1200),
            net: SweepNetConfig::default(),
            steps: 3000,
            batch: 256,
            band_rows: 8,
            lr: 1e-3,
            frame_every: 4,
            log_every: 100,
            grid: (160, 640, 192),
            seed: 0,
        }
    }
}

/// One metrics line.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepRecord {
    pub step: usize,
    pub train_loss: f32,
    /// Share of training pixels whose lowest cost is within one hypothesis of the truth.
    pub train_acc: f32,
    pub val_loss: f32,
    pub val_acc: f32,
    /// The same share for the plain ZNCC cost on the validation pixels.
    pub val_zncc_acc: f32,
    pub seconds: f64,
}

/// One frame ready for drawing samples.
pub struct Frame {
    source: usize,
    views: Vec<CameraView>,
    gt: GroundTruth,
}

fn load_frame(sources: &[Source], source: usize, frame: u32) -> Result<Frame, TrainError> {
    let s = &sources[source];
    let images = s.dataset.read_frame(frame)?;
    let views = images
        .iter()
        .zip(&s.masks)
        .enumerate()
        .map(|(i, (img, m))| CameraView::new(img, Some(m), i + 1))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| TrainError::InvalidConfig {
            field: "data",
            message: format!("{}: frame {frame}: {e}", s.dataset.root.display()),
        })?;
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
    Ok(Frame { source, views, gt })
}

/// Pixels with the window features of every sphere.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepBatch {
    /// `[pixel][sphere][feature]`.
    pub features: Vec<f32>,
    /// Ground-truth index of each pixel.
    pub target: Vec<f32>,
    pub ndepth: usize,
    pub dim: usize,
}

impl SweepBatch {
    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.target.len()
    }

    pub fn is_empty(&self) -> bool {
        self.target.is_empty()
    }
}

fn draw_batch(
    sources: &[Source],
    frame: &Frame,
    config: &SweepTrainConfig,
    rng: &mut SplitMix64,
) -> SweepBatch {
    let src = &sources[frame.source];
    let grid = &src.spec.grid;
    let hyps = &src.spec.hypotheses;
    let (w, h, nd) = (grid.width, grid.height, hyps.count);
    let dim = config.net.layout().dim();
    let rows = config.band_rows.min(h);
    let r0 = rng.below(h - rows + 1);
    let mut candidates: Vec<usize> = (r0 * w..(r0 + rows) * w)
        .filter(|&i| frame.gt.valid[i] && frame.gt.index[i] >= 0.5)
        .collect();
    // A partial Fisher-Yates shuffle picks the batch.
    let take = config.batch.min(candidates.len());
    for k in 0..take {
        let j = k + rng.below(candidates.len() - k);
        candidates.swap(k, j);
    }
    let picked = &candidates[..take];
    let spec = config.net.spec();
    let per_sphere: Vec<Vec<f32>> = (0..nd)
        .into_par_iter()
        .map_init(
            || (BandScratch::default(), vec![0f32; rows * w * dim]),
            |(scratch, band), n| {
                band_features(
                    grid,
                    &src.projectors,
                    &frame.views,
                    &spec,
                    r0..r0 + rows,
                    hyps.inv_depth(n as f64) as f32,
                    scratch,
                    band,
                );
                picked
                    .iter()
                    .flat_map(|&i| band[(i - r0 * w) * dim..][..dim].iter().copied())
                    .collect()
            },
        )
        .collect();
    let mut features = vec![0f32; take * nd * dim];
    for (n, sphere) in per_sphere.iter().enumerate() {
        for b in 0..take {
            features[(b * nd + n) * dim..][..dim].copy_from_slice(&sphere[b * dim..][..dim]);
        }
    }
    SweepBatch {
        features,
        target: picked.iter().map(|&i| frame.gt.index[i]).collect(),
        ndepth: nd,
        dim,
    }
}

/// Share of pixels whose lowest cost (`costs` is `[pixel][sphere]`) is within one hypothesis
/// of `target`.
pub fn within_one(costs: &[f32], target: &[f32], ndepth: usize) -> f32 {
    let hits = costs
        .chunks_exact(ndepth)
        .zip(target)
        .filter(|(c, t)| {
            let best = c
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(n, _)| n);
            (best as f32 - **t).abs() <= 1.0
        })
        .count();
    hits as f32 / target.len().max(1) as f32
}

/// The plain ZNCC cost (`(1 - zncc) / 2` averaged over complete pairs) of every feature
/// vector of a batch, `[pixel][sphere]`.
pub fn zncc_costs(batch: &SweepBatch, layout: FeatureLayout) -> Vec<f32> {
    batch
        .features
        .chunks_exact(batch.dim)
        .map(|f| layout.zncc_cost(f))
        .collect()
}

/// Cross-entropy of the softmin over the spheres against the ground truth, and the share of
/// pixels whose lowest cost is within one hypothesis of it.
pub fn batch_loss(net: &SweepNet, batch: &SweepBatch, device: &Device) -> (Tensor<1>, f32) {
    let (b, nd, dim) = (batch.len(), batch.ndepth, batch.dim);
    let x = Tensor::<2>::from_data(
        TensorData::new(batch.features.clone(), [b * nd, dim]),
        device,
    );
    let costs = net.costs(x).reshape([b, nd]);
    let logp = activation::log_softmax(costs.clone().mul_scalar(-net.config.temperature), 1);
    let mut soft = vec![0f32; b * nd];
    for (k, &t) in batch.target.iter().enumerate() {
        let t = t.clamp(0.0, (nd - 1) as f32);
        let lo = t.floor() as usize;
        let frac = t - lo as f32;
        soft[k * nd + lo] += 1.0 - frac;
        if lo + 1 < nd {
            soft[k * nd + lo + 1] += frac;
        }
    }
    let target = Tensor::<2>::from_data(TensorData::new(soft, [b, nd]), device);
    let loss = (target * logp).sum_dim(1).mean().neg();
    let values = costs.into_data().try_into_vec::<f32>().unwrap_or_default();
    let acc = within_one(&values, &batch.target, nd);
    (loss, acc)
}

/// A SweepNet training run.
pub type SweepTrainer = CostModelTrainer<SweepTrainConfig>;

impl CostModel for SweepTrainConfig {
    type Net = SweepNet;
    type Frame = Frame;
    type Batch = SweepBatch;
    type Record = SweepRecord;

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
        if self.batch == 0 || self.band_rows == 0 || self.frame_every == 0 {
            return Err(TrainError::InvalidConfig {
                field: "batch",
                message: "expected batch > 0, band_rows > 0, frame_every > 0".into(),
            });
        }
        Ok(())
    }

    /// Every dataset's rig has the cameras the network reads.
    fn check_sources(&self, sources: &[Source]) -> Result<(), TrainError> {
        let cameras = self.net.cameras;
        match sources.iter().find(|s| s.dataset.rig.len() != cameras) {
            Some(s) => Err(TrainError::InvalidConfig {
                field: "data",
                message: format!(
                    "{}: {} cameras, the network reads {cameras}",
                    s.dataset.root.display(),
                    s.dataset.rig.len(),
                ),
            }),
            None => Ok(()),
        }
    }

    fn build(&self, device: &Device) -> Result<SweepNet, TrainError> {
        Ok(SweepNet::new(&self.net, device)?)
    }

    fn load_frame(
        &self,
        sources: &[Source],
        source: usize,
        frame: u32,
    ) -> Result<Frame, TrainError> {
        load_frame(sources, source, frame)
    }

    fn draw(&self, sources: &[Source], frame: &Frame, rng: &mut SplitMix64) -> Option<SweepBatch> {
        let batch = draw_batch(sources, frame, self, rng);
        (!batch.is_empty()).then_some(batch)
    }

    /// Two bands of the frame, the empty ones left out.
    fn validation_batches(
        &self,
        sources: &[Source],
        frame: &Frame,
        source: usize,
        j: usize,
    ) -> Vec<SweepBatch> {
        (0..2u64)
            .filter_map(|k| {
                let mut rng = SplitMix64::new(0x5EED ^ (source as u64 * 31 + j as u64 * 7 + k));
                self.draw(sources, frame, &mut rng)
            })
            .collect()
    }

    fn loss(&self, net: &SweepNet, batch: &SweepBatch, device: &Device) -> (Tensor<1>, f32) {
        batch_loss(net, batch, device)
    }

    /// With the share of the plain ZNCC cost on the validation pixels.
    fn record(&self, p: &Progress, val: &[SweepBatch]) -> SweepRecord {
        let layout = self.net.layout();
        let zncc_acc = val
            .iter()
            .map(|b| within_one(&zncc_costs(b, layout), &b.target, b.ndepth))
            .sum::<f32>()
            / val.len().max(1) as f32;
        SweepRecord {
            step: p.step,
            train_loss: p.train_loss,
            train_acc: p.train_acc,
            val_loss: p.val_loss,
            val_acc: p.val_acc,
            val_zncc_acc: zncc_acc,
            seconds: p.seconds,
        }
    }

    fn save(net: &SweepNet, path: &Path) -> Result<(), TrainError> {
        Ok(sweepnet::save(net, path)?)
    }
}
