//! Forward-pass and training-step benchmarks on synthetic inputs, per stage, with peak memory.
//! Used by `omnimvs bench` and the memory test of the paper preset; the cascade's forward
//! pass and training step run on a real rig (its per-pixel sampler needs camera models).

use std::f32::consts::PI;
use std::time::Instant;

use burn::tensor::{Device, Distribution, Tensor};
use omnimvs_data::gt::GroundTruth;
use serde::Serialize;

use burn::module::Module;
use omnimvs_camera::Rig;
use omnimvs_sweep::InvDepthHypotheses;

use crate::cascade::{CascadeGeometry, CascadeNet, CascadeTimings};
use crate::config::NetConfig;
use crate::error::NetError;
use crate::model::{OmniMvsNet, StageTimings, SweepInput, SweepTaps};
use crate::taps::SweepGrid;
use crate::train::{Learner, Optimizer, Sample, TrainConfig};

/// Half field of view of the synthetic fisheyes, degrees (220 degree lenses).
const HALF_FOV_DEG: f32 = 110.0;

/// Result of [`bench_forward`].
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// The configuration measured.
    pub config: NetConfig,
    /// Whether batch norms were folded into the convolutions.
    pub folded_batch_norm: bool,
    /// Timings of every measured run (the warm-up run excluded).
    pub runs: Vec<StageTimingsRow>,
    /// Peak resident memory of the process after the runs, bytes (Linux only).
    pub peak_rss_bytes: Option<u64>,
    /// Fraction of sweep samples inside some camera's field of view.
    pub valid_fraction: f64,
}

/// [`StageTimings`] in a serialisable row.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct StageTimingsRow {
    /// Unary features, seconds.
    pub features: f64,
    /// Warp + transference, seconds.
    pub sweep: f64,
    /// Fusion convolution, batch norm and ReLU, seconds.
    pub fusion: f64,
    /// 3D encoder-decoder, seconds.
    pub cost: f64,
    /// Softargmin, seconds.
    pub softargmin: f64,
    /// Whole forward pass, seconds.
    pub total: f64,
}

impl From<StageTimings> for StageTimingsRow {
    fn from(t: StageTimings) -> Self {
        Self {
            features: t.features,
            sweep: t.sweep,
            fusion: t.fusion + t.fusion_finish,
            cost: t.cost,
            softargmin: t.softargmin,
            total: t.total,
        }
    }
}

/// The median of `f` over `runs` (the upper one for an even count); `runs` is not empty.
fn median_of<T>(runs: &[T], f: fn(&T) -> f64) -> f64 {
    let mut v: Vec<f64> = runs.iter().map(f).collect();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

impl BenchReport {
    /// Median of each stage over the runs.
    pub fn median(&self) -> Option<StageTimingsRow> {
        if self.runs.is_empty() {
            return None;
        }
        let med = |f| median_of(&self.runs, f);
        Some(StageTimingsRow {
            features: med(|r| r.features),
            sweep: med(|r| r.sweep),
            fusion: med(|r| r.fusion),
            cost: med(|r| r.cost),
            softargmin: med(|r| r.softargmin),
            total: med(|r| r.total),
        })
    }
}

/// Peak resident set size of this process in bytes (`VmHWM`), `None` off Linux.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// A synthetic lookup table: camera `i` looks horizontally along azimuth `i * 360 / cams`
/// with an equidistant 220 degree fisheye; the spheres shift the samples slightly like a
/// baseline would. Samples outside the field of view are invalid (far outside the image).
pub fn synthetic_grids(config: &NetConfig) -> Vec<SweepGrid> {
    let (h, w, n) = (config.out_height, config.out_width, config.num_spheres());
    let phi_max = (config.phi_deg as f32).to_radians();
    (0..config.num_cameras)
        .map(|cam| {
            let yaw = 2.0 * PI * cam as f32 / config.num_cameras as f32;
            let mut coords = Vec::with_capacity(n * h * w * 2);
            for s in 0..n {
                let shift = 0.02 * s as f32 / n as f32;
                for row in 0..h {
                    let phi =
                        (row as f32 - (h as f32 - 1.0) / 2.0) / ((h as f32 - 1.0) / 2.0) * phi_max;
                    for col in 0..w {
                        let theta = (col as f32 - w as f32 / 2.0) / (w as f32 / 2.0) * PI - yaw;
                        // Ray in the camera frame: z forward, x right, y down.
                        let (x, y, z) =
                            (phi.cos() * theta.sin(), phi.sin(), phi.cos() * theta.cos());
                        let angle = z.clamp(-1.0, 1.0).acos();
                        if angle.to_degrees() > HALF_FOV_DEG {
                            coords.extend([-1e5f32, -1e5]);
                            continue;
                        }
                        let r = angle / HALF_FOV_DEG.to_radians() + shift;
                        let norm = (x * x + y * y).sqrt().max(f32::EPSILON);
                        coords.extend([r * x / norm, r * y / norm]);
                    }
                }
            }
            SweepGrid {
                num_spheres: n,
                height: h,
                width: w,
                coords,
            }
        })
        .collect()
}

/// Runs the memory-lean inference on random images `1 + repeats` times (the first run is a
/// warm-up) and reports the stage timings; the sweep runs on the host.
///
/// # Errors
/// [`NetError`] for an invalid configuration.
pub fn bench_forward(
    config: &NetConfig,
    repeats: usize,
    fold_batch_norm: bool,
    device: &Device,
) -> Result<BenchReport, NetError> {
    let options = ForwardOptions {
        repeats,
        fold_batch_norm,
        ..ForwardOptions::default()
    };
    bench_forward_with(config, &options, device)
}

/// Options of [`bench_forward_with`].
#[derive(Clone, Copy, Debug)]
pub struct ForwardOptions {
    /// Unmeasured runs first.
    pub warmup: usize,
    /// Measured runs.
    pub repeats: usize,
    /// Fold the batch norms into the convolutions.
    pub fold_batch_norm: bool,
    /// Sweep on the device (GPU backends) instead of the host.
    pub device_sweep: bool,
}

impl Default for ForwardOptions {
    fn default() -> Self {
        Self {
            warmup: 1,
            repeats: 3,
            fold_batch_norm: true,
            device_sweep: false,
        }
    }
}

/// [`bench_forward`] with all options.
///
/// # Errors
/// [`NetError`] for an invalid configuration.
pub fn bench_forward_with(
    config: &NetConfig,
    options: &ForwardOptions,
    device: &Device,
) -> Result<BenchReport, NetError> {
    let ForwardOptions {
        warmup,
        repeats,
        fold_batch_norm,
        device_sweep,
    } = *options;
    let net = OmniMvsNet::new(config, device)?;
    let net = if fold_batch_norm {
        net.fold_batch_norm()
    } else {
        net
    };
    let grids = synthetic_grids(config);
    let valid = grids
        .iter()
        .flat_map(|g| g.coords.chunks_exact(2))
        .filter(|xy| xy[0] > -2.0)
        .count();
    let total: usize = grids.iter().map(|g| g.coords.len() / 2).sum();
    let taps: Vec<SweepTaps> = if device_sweep {
        SweepTaps::for_grids(&grids, config.feature_size(), device)
    } else {
        Vec::new()
    };
    let sweep = if device_sweep {
        SweepInput::Device(&taps)
    } else {
        SweepInput::Host(&grids)
    };
    let images = random_images(config, device);
    let order = net.identity_order();
    let mut runs = Vec::new();
    for run in 0..warmup + repeats {
        let (_, timings) = net.infer_timed_with(&images, sweep, &order)?;
        if run >= warmup {
            runs.push(timings.into());
        }
    }
    Ok(BenchReport {
        config: config.clone(),
        folded_batch_norm: fold_batch_norm,
        runs,
        peak_rss_bytes: peak_rss_bytes(),
        valid_fraction: valid as f64 / total.max(1) as f64,
    })
}

/// Random `[1, 1, H_I, W_I]` images, one per camera.
fn random_images(config: &NetConfig, device: &Device) -> Vec<Tensor<4>> {
    (0..config.num_cameras)
        .map(|_| {
            Tensor::random(
                [1, 1, config.input_height, config.input_width],
                Distribution::Normal(0.0, 1.0),
                device,
            )
        })
        .collect()
}

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
/// [`NetError`] for an invalid configuration.
pub fn bench_train_step(
    config: &NetConfig,
    warmup: usize,
    steps: usize,
    device: &Device,
) -> Result<TrainStepReport, NetError> {
    let train = TrainConfig {
        net: config.clone(),
        ..TrainConfig::default()
    };
    let mut learner = Learner::new(&train, device)?;
    let taps = learner.taps(&synthetic_grids(config));
    let cells = config.out_height * config.out_width;
    let n_max = (config.num_invdepth - 1) as f32;
    let sample = Sample {
        source: 0,
        frame: 0,
        rotation: 0,
        images: (0..config.num_cameras)
            .map(|cam| {
                (0..config.input_height * config.input_width)
                    .map(|i| ((i * 7 + cam * 13) % 29) as f32 / 14.0 - 1.0)
                    .collect()
            })
            .collect(),
        gt: GroundTruth {
            width: config.out_width,
            height: config.out_height,
            index: (0..cells).map(|i| (i % 97) as f32 / 96.0 * n_max).collect(),
            valid: vec![true; cells],
        },
        stage_gt: Vec::new(),
        window: None,
    };
    let order = learner.net.identity_order();
    let mut report = TrainStepReport {
        steps: Vec::new(),
        losses: Vec::new(),
        peak_rss_bytes: None,
    };
    for step in 0..warmup + steps {
        let start = Instant::now();
        let loss = learner.step(&sample, &taps, &order, 0.003)?; // reads the loss: synchronises
        let _ = learner.device.sync();
        if step >= warmup {
            report.steps.push(start.elapsed().as_secs_f64());
            report.losses.push(loss);
        }
    }
    report.peak_rss_bytes = peak_rss_bytes();
    Ok(report)
}

/// One forward pass of the cascade, seconds per stage.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct CascadeRow {
    /// Feature pyramids of all cameras.
    pub features: f64,
    /// Coarse volume, regularisation, soft argmax.
    pub coarse: f64,
    /// Half-resolution stage (hypotheses and taps on the host included).
    pub mid: f64,
    /// Full-resolution stage (likewise).
    pub fine: f64,
    /// Whole forward pass.
    pub total: f64,
}

impl From<CascadeTimings> for CascadeRow {
    fn from(t: CascadeTimings) -> Self {
        Self {
            features: t.features,
            coarse: t.coarse,
            mid: t.mid,
            fine: t.fine,
            total: t.total,
        }
    }
}

/// Result of [`bench_cascade_forward`].
#[derive(Clone, Debug, Serialize)]
pub struct CascadeBenchReport {
    /// The configuration measured.
    pub config: NetConfig,
    /// Number of parameters of the network.
    pub params: usize,
    /// Timings of every measured run (warm-up runs excluded).
    pub runs: Vec<CascadeRow>,
    /// Peak resident memory of the process after the runs, bytes (Linux only).
    pub peak_rss_bytes: Option<u64>,
}

impl CascadeBenchReport {
    /// Median of each stage over the runs.
    pub fn median(&self) -> Option<CascadeRow> {
        if self.runs.is_empty() {
            return None;
        }
        let med = |f| median_of(&self.runs, f);
        Some(CascadeRow {
            features: med(|r| r.features),
            coarse: med(|r| r.coarse),
            mid: med(|r| r.mid),
            fine: med(|r| r.fine),
            total: med(|r| r.total),
        })
    }
}

/// Times the cascade's forward pass per stage on random images for `rig` (random weights,
/// inference mode, `warmup` unmeasured runs first).
///
/// # Errors
/// [`NetError`] for a configuration that is not a cascade or a rig that does not fit it.
pub fn bench_cascade_forward(
    config: &NetConfig,
    rig: &Rig,
    min_depth_m: f64,
    warmup: usize,
    repeats: usize,
    device: &Device,
) -> Result<CascadeBenchReport, NetError> {
    let net = CascadeNet::new(config, device)?.valid();
    let hypotheses = InvDepthHypotheses::new(config.num_invdepth, min_depth_m)?;
    let geometry = CascadeGeometry::new(rig, config, &hypotheses, device)?;
    let images = random_images(config, device);
    let mut runs = Vec::new();
    for run in 0..warmup + repeats {
        let (_, timings) = net.forward_timed(&images, &geometry, true)?;
        if run >= warmup {
            runs.push(timings.into());
        }
    }
    Ok(CascadeBenchReport {
        config: config.clone(),
        params: net.num_params(),
        runs,
        peak_rss_bytes: peak_rss_bytes(),
    })
}

/// Times the cascade's training step (forward, the three stages' L1 losses, backward, Adam)
/// on one sample of random images and a ramp of ground truth for `rig`.
///
/// # Errors
/// [`NetError`] for a configuration that is not a cascade or a rig that does not fit it.
pub fn bench_cascade_train_step(
    config: &NetConfig,
    rig: &Rig,
    min_depth_m: f64,
    warmup: usize,
    steps: usize,
    device: &Device,
) -> Result<TrainStepReport, NetError> {
    let train = TrainConfig {
        net: config.clone(),
        optimizer: Optimizer::Adam,
        ..TrainConfig::default()
    };
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
    let sample = Sample {
        source: 0,
        frame: 0,
        rotation: 0,
        images: (0..config.num_cameras)
            .map(|cam| {
                (0..config.input_height * config.input_width)
                    .map(|i| ((i * 7 + cam * 13) % 29) as f32 / 14.0 - 1.0)
                    .collect()
            })
            .collect(),
        gt: ramp(fine),
        stage_gt: vec![ramp(coarse), ramp(mid)],
        window: None,
    };
    let mut report = TrainStepReport {
        steps: Vec::new(),
        losses: Vec::new(),
        peak_rss_bytes: None,
    };
    for step in 0..warmup + steps {
        let start = Instant::now();
        let loss = learner.step(&sample, &geometry, &[], 0.001)?; // reads the loss: synchronises
        let _ = learner.device.sync();
        if step >= warmup {
            report.steps.push(start.elapsed().as_secs_f64());
            report.losses.push(loss);
        }
    }
    report.peak_rss_bytes = peak_rss_bytes();
    Ok(report)
}
