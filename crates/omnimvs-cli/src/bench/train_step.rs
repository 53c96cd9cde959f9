//! Training-step timings of both network families: forward, loss, backward, optimiser.

use std::time::Instant;

use anyhow::Result;
use burn::tensor::Device;
use omnimvs_camera::Rig;
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::cascade::{CascadeGeometry, CascadeNet};
use omnimvs_net::config::NetConfig;
use omnimvs_net::synthetic::synthetic_grids;
use omnimvs_sweep::InvDepthHypotheses;
use omnimvs_train::{Learner, Optimizer, Sample, TrainConfig};
use serde::Serialize;

use super::peak_rss_bytes;

/// Result of [`bench_train_step`].
#[derive(Clone, Debug, Serialize)]
pub struct TrainStepReport {
    /// Seconds of every measured step (forward, backward, SGD update), the warm-up excluded.
    pub steps: Vec<f64>,
    /// The loss before each measured step.
    pub losses: Vec<f32>,
    /// Peak resident memory of the process after the steps, bytes (Linux only).
    pub peak_rss_bytes: Option<u64>,
}

impl TrainStepReport {
    /// Median step time, seconds.
    pub fn median(&self) -> Option<f64> {
        let mut v = self.steps.clone();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    }
}

/// Times `warmup + steps` training steps (the first `warmup` unmeasured) on one sample with a
/// random ground truth: the paper's masked L1, backward through the whole network including
/// the sweep taps, and the SGD-momentum update, on `device` with autodiff.
///
/// # Errors
/// For an invalid configuration.
pub fn bench_train_step(
    config: &NetConfig,
    warmup: usize,
    steps: usize,
    device: &Device,
) -> Result<TrainStepReport> {
    let train = train_config(config, TrainConfig::default().optimizer);
    let mut learner = Learner::new(&train, device)?;
    let taps = learner.taps(&synthetic_grids(config));
    let cells = config.out_height * config.out_width;
    let n_max = (config.num_invdepth - 1) as f32;
    let gt = GroundTruth {
        width: config.out_width,
        height: config.out_height,
        index: (0..cells).map(|i| (i % 97) as f32 / 96.0 * n_max).collect(),
        valid: vec![true; cells],
    };
    let sample = bench_sample(config, gt, Vec::new());
    let order = learner.net.identity_order();
    time_steps(warmup, steps, || {
        let loss = learner.step(&sample, &taps, &order, 0.003)?; // reads the loss: synchronises
        let _ = learner.device.sync();
        Ok(loss)
    })
}

/// Times the cascade's training step (forward, the three stages' L1 losses, backward, Adam)
/// on one sample of random images and a ramp of ground truth for `rig`.
///
/// # Errors
/// For a configuration that is not a cascade or a rig that does not fit it.
pub fn bench_cascade_train_step(
    config: &NetConfig,
    rig: &Rig,
    min_depth_m: f64,
    warmup: usize,
    steps: usize,
    device: &Device,
) -> Result<TrainStepReport> {
    let train = train_config(config, Optimizer::Adam);
    let mut learner = Learner::<CascadeNet>::for_model(&train, device)?;
    let hypotheses = InvDepthHypotheses::new(config.num_invdepth, min_depth_m)?;
    let geometry = CascadeGeometry::new(rig, config, &hypotheses, &learner.device)?;
    let n_max = (config.num_invdepth - 1) as f32;
    let ramp = |[h, w]: [usize; 2]| GroundTruth {
        width: w,
        height: h,
        index: (0..h * w)
            .map(|i| (i % w) as f32 / w as f32 * n_max)
            .collect(),
        valid: vec![true; h * w],
    };
    let [coarse, mid, fine] = config.cascade_sizes();
    let sample = bench_sample(config, ramp(fine), vec![ramp(coarse), ramp(mid)]);
    time_steps(warmup, steps, || {
        let loss = learner.step(&sample, &geometry, &[], 0.001)?; // reads the loss: synchronises
        let _ = learner.device.sync();
        Ok(loss)
    })
}

/// The training configuration of a benchmark: `config`'s network and `optimizer`.
fn train_config(config: &NetConfig, optimizer: Optimizer) -> TrainConfig {
    TrainConfig {
        net: config.clone(),
        optimizer,
        ..TrainConfig::default()
    }
}

/// The one sample a benchmark trains on: [`test_images`] with the ground truth `gt` and, for
/// the cascade, `stage_gt`.
fn bench_sample(config: &NetConfig, gt: GroundTruth, stage_gt: Vec<GroundTruth>) -> Sample {
    Sample {
        source: 0,
        frame: 0,
        rotation: 0,
        images: test_images(config),
        gt,
        stage_gt,
        window: None,
    }
}

/// Deterministic images in `[-1, 1]` for every camera of `config`, at its input size.
fn test_images(config: &NetConfig) -> Vec<Vec<f32>> {
    (0..config.num_cameras)
        .map(|cam| {
            (0..config.input_height * config.input_width)
                .map(|i| ((i * 7 + cam * 13) % 29) as f32 / 14.0 - 1.0)
                .collect()
        })
        .collect()
}

/// Runs `step` (one training step, returning its loss) `warmup + steps` times and records the
/// time and loss of all but the first `warmup`, then the process's peak memory.
fn time_steps(
    warmup: usize,
    steps: usize,
    mut step: impl FnMut() -> Result<f32>,
) -> Result<TrainStepReport> {
    let mut report = TrainStepReport {
        steps: Vec::new(),
        losses: Vec::new(),
        peak_rss_bytes: None,
    };
    for i in 0..warmup + steps {
        let start = Instant::now();
        let loss = step()?;
        if i >= warmup {
            report.steps.push(start.elapsed().as_secs_f64());
            report.losses.push(loss);
        }
    }
    report.peak_rss_bytes = peak_rss_bytes();
    Ok(report)
}
