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

use burn::module::Module;
use burn::tensor::{Device, Tensor, TensorData, activation};
use omnimvs_core::GrayImage;
use omnimvs_core::interp::mix_2d;
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::mccnn::{self, McCnn, McCnnConfig, pool};
use serde::{Deserialize, Serialize};

use crate::cost_run::{RunState, Schedule, Source, append_metrics, read_run_config};
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

impl CostTrainConfig {
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
struct Frame {
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

/// A matching-cost training run.
pub struct CostTrainer {
    pub config: CostTrainConfig,
    state: RunState<McCnn>,
}

impl CostTrainer {
    /// A new run in `run_dir` (created; refused if it holds a run already).
    ///
    /// # Errors
    /// [`TrainError`] for unreadable datasets or an existing run.
    pub fn create(
        config: CostTrainConfig,
        run_dir: &Path,
        device: &Device,
    ) -> Result<Self, TrainError> {
        if config.batch == 0 || config.neg_max < config.neg_min || config.frame_every == 0 {
            return Err(TrainError::InvalidConfig {
                field: "batch",
                message: "expected batch > 0, neg_max >= neg_min, frame_every > 0".into(),
            });
        }
        let state = RunState::create(
            run_dir,
            &config,
            &config.data,
            config.grid,
            config.seed,
            device,
            |_| Ok(()),
            |d| Ok(McCnn::new(&config.net, d)?),
        )?;
        Ok(Self { config, state })
    }

    /// The run in `run_dir` from its last checkpoint; `steps` raises the total.
    ///
    /// # Errors
    /// [`TrainError`] for a missing or unreadable run.
    pub fn resume(
        run_dir: &Path,
        steps: Option<usize>,
        device: &Device,
    ) -> Result<Self, TrainError> {
        let mut config: CostTrainConfig = read_run_config(run_dir)?;
        if let Some(s) = steps {
            config.steps = s;
        }
        let state = RunState::resume(run_dir, &config.data, config.grid, device, |d| {
            Ok(McCnn::new(&config.net, d)?)
        })?;
        Ok(Self { config, state })
    }

    /// The step the run is at.
    pub fn step(&self) -> usize {
        self.state.step
    }

    /// The run's folder.
    pub fn run_dir(&self) -> &Path {
        &self.state.run_dir
    }

    /// Fixed validation batches: two frames of each dataset's validation range.
    fn validation(&self) -> Result<Vec<Vec<f32>>, TrainError> {
        let mut out = Vec::new();
        let (v0, v1) = self.config.val_frames;
        for s in 0..self.state.sources.len() {
            for (j, f) in [v0, v1].into_iter().enumerate() {
                let frame = load_frame(&self.state.sources, s, f, self.config.net.stride)?;
                let mut rng = SplitMix64::new(0x5EED ^ (s as u64 * 31 + j as u64));
                out.push(draw_batch(
                    &self.state.sources,
                    &frame,
                    &self.config,
                    &mut rng,
                ));
            }
        }
        Ok(out)
    }

    /// Trains up to `self.config.steps` (or `stop_after` more steps), calling `report`
    /// with each metrics line.
    ///
    /// # Errors
    /// [`TrainError`] for unreadable frames or unwritable files.
    pub fn run(
        &mut self,
        stop_after: Option<usize>,
        mut report: impl FnMut(&CostRecord),
    ) -> Result<(), TrainError> {
        let val = self.validation()?;
        let config = &self.config;
        self.state.train(
            &config.schedule(),
            stop_after,
            &val,
            |sources, s, f| load_frame(sources, s, f, config.net.stride),
            |sources, frame, rng| {
                let patches = draw_batch(sources, frame, config, rng);
                (!patches.is_empty()).then_some(patches)
            },
            |net, patches, device| batch_loss(net, patches.clone(), config.margin, device),
            |state, record| {
                append_metrics(&state.run_dir, record)?;
                state.save_checkpoint()?;
                mccnn::save(&state.net.valid(), &state.run_dir.join("model.safetensors"))?;
                report(record);
                Ok(())
            },
        )
    }

    /// The trained network, without autodiff.
    pub fn net(&self) -> McCnn {
        self.state.net.valid()
    }
}
