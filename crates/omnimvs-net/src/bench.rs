//! Forward-pass benchmark on synthetic inputs, per stage, with peak memory. Used by the
//! criterion bench, the `bench_forward` example and the CLI.

use std::f32::consts::PI;

use burn::tensor::{Device, Distribution, Tensor};
use serde::Serialize;

use crate::config::NetConfig;
use crate::error::NetError;
use crate::model::{OmniMvsNet, StageTimings};
use crate::taps::SweepGrid;

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

impl BenchReport {
    /// Median of each stage over the runs.
    pub fn median(&self) -> Option<StageTimingsRow> {
        if self.runs.is_empty() {
            return None;
        }
        let med = |f: fn(&StageTimingsRow) -> f64| {
            let mut v: Vec<f64> = self.runs.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
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
/// warm-up) and reports the stage timings.
///
/// # Errors
/// [`NetError`] for an invalid configuration.
pub fn bench_forward(
    config: &NetConfig,
    repeats: usize,
    fold_batch_norm: bool,
    device: &Device,
) -> Result<BenchReport, NetError> {
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
    let images: Vec<Tensor<4>> = (0..config.num_cameras)
        .map(|_| {
            Tensor::random(
                [1, 1, config.input_height, config.input_width],
                Distribution::Normal(0.0, 1.0),
                device,
            )
        })
        .collect();
    let order = net.identity_order();
    let mut runs = Vec::new();
    for run in 0..=repeats {
        let (_, timings) = net.infer_timed(&images, &grids, &order)?;
        if run > 0 {
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
