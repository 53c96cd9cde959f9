//! Forward-pass timings per stage of both network families.

use anyhow::Result;
use burn::module::Module;
use burn::tensor::Device;
use omnimvs_camera::Rig;
use omnimvs_core::GrayImage;
use omnimvs_net::cascade::{CascadeGeometry, CascadeNet, CascadeTimings};
use omnimvs_net::config::NetConfig;
use omnimvs_net::model::{OmniMvsNet, StageTimings, SweepInput, SweepTaps};
use omnimvs_net::pick::PickRefiner;
use omnimvs_net::synthetic::synthetic_grids;
use omnimvs_net::tensor::read_values;
use omnimvs_sweep::InvDepthHypotheses;
use serde::Serialize;

use super::{median_row, peak_rss_bytes, random_images};

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
        median_row(&self.runs, |med| StageTimingsRow {
            features: med(|r| r.features),
            sweep: med(|r| r.sweep),
            fusion: med(|r| r.fusion),
            cost: med(|r| r.cost),
            softargmin: med(|r| r.softargmin),
            total: med(|r| r.total),
        })
    }
}

/// Options of [`bench_forward`].
#[derive(Clone, Copy, Debug)]
pub struct ForwardOptions {
    /// Unmeasured runs first.
    pub warmup: usize,
    /// Measured runs.
    pub repeats: usize,
    /// Fold the batch norms into the convolutions.
    pub fold_batch_norm: bool,
    /// Sweep (the cascade: its correlation) on the device (GPU backends) instead of the host.
    pub device_sweep: bool,
    /// The convolutions on the host kernels (`omnimvs_net::hostconv`, what `infer` does on
    /// burn flex) once the batch norms are folded; burn's otherwise.
    pub host_convs: bool,
}

impl Default for ForwardOptions {
    fn default() -> Self {
        Self {
            warmup: 1,
            repeats: 3,
            fold_batch_norm: true,
            device_sweep: false,
            host_convs: true,
        }
    }
}

/// Runs the memory-lean inference on random images `warmup + repeats` times (the warm-up
/// runs are not measured) and reports the stage timings, the sweep on the host or the device.
///
/// # Errors
/// For an invalid configuration.
pub fn bench_forward(
    config: &NetConfig,
    options: &ForwardOptions,
    device: &Device,
) -> Result<BenchReport> {
    let ForwardOptions {
        warmup,
        repeats,
        fold_batch_norm,
        device_sweep,
        host_convs,
    } = *options;
    let net = OmniMvsNet::new(config, device)?;
    let net = match (fold_batch_norm, host_convs) {
        (true, true) => net.fold_batch_norm().with_host_convs(),
        (true, false) => net.fold_batch_norm(),
        _ => net,
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
    /// The learnt pick after the network (its inputs included; 0 without it).
    pub pick: f64,
    /// Whole forward pass, the pick included.
    pub total: f64,
}

impl From<CascadeTimings> for CascadeRow {
    fn from(t: CascadeTimings) -> Self {
        Self {
            features: t.features,
            coarse: t.coarse,
            mid: t.mid,
            fine: t.fine,
            pick: 0.0,
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
    /// Whether batch norms were folded into the convolutions (as `infer` runs it).
    pub folded_batch_norm: bool,
    /// Whether the convolutions ran on the host kernels (as `infer` runs them on a CPU).
    pub host_convs: bool,
    /// Whether the learnt pick ran after the network.
    pub pick: bool,
    /// Timings of every measured run (warm-up runs excluded).
    pub runs: Vec<CascadeRow>,
    /// Peak resident memory of the process after the runs, bytes (Linux only).
    pub peak_rss_bytes: Option<u64>,
}

impl CascadeBenchReport {
    /// Median of each stage over the runs.
    pub fn median(&self) -> Option<CascadeRow> {
        median_row(&self.runs, |med| CascadeRow {
            features: med(|r| r.features),
            coarse: med(|r| r.coarse),
            mid: med(|r| r.mid),
            fine: med(|r| r.fine),
            pick: med(|r| r.pick),
            total: med(|r| r.total),
        })
    }
}

/// Times the cascade's forward pass per stage on random images for `rig` (random weights,
/// inference mode, `options.warmup` unmeasured runs first). `options` say whether the batch
/// norms are folded and the correlation runs on the device; `infer` folds them and correlates
/// on the host on a CPU. With `pick`, the learnt pick runs after each pass on its answer (random
/// images of the rig's sizes, the spread at 0), as `infer` runs it after the bundled cascade.
///
/// # Errors
/// For a configuration that is not a cascade or a rig that does not fit it.
pub fn bench_cascade_forward(
    config: &NetConfig,
    rig: &Rig,
    min_depth_m: f64,
    options: ForwardOptions,
    pick: Option<&PickRefiner>,
    device: &Device,
) -> Result<CascadeBenchReport> {
    let net = CascadeNet::new(config, device)?.valid();
    // The network's own parameters, batch norms included (folding merges them).
    let params = net.num_params();
    let ForwardOptions {
        warmup,
        repeats,
        fold_batch_norm,
        device_sweep,
        host_convs,
    } = options;
    let host_convs = host_convs && fold_batch_norm;
    let net = match (fold_batch_norm, host_convs) {
        (true, true) => net.fold_batch_norm().with_host_convs(),
        (true, false) => net.fold_batch_norm(),
        _ => net,
    };
    let hypotheses = InvDepthHypotheses::new(config.num_invdepth, min_depth_m)?;
    let geometry =
        CascadeGeometry::with_host_correlation(rig, config, &hypotheses, device, !device_sweep)?;
    let images = random_images(config, device);
    let gray: Vec<GrayImage> = rig
        .cameras
        .iter()
        .enumerate()
        .map(|(c, camera)| {
            let (w, h) = (
                camera.model.width() as usize,
                camera.model.height() as usize,
            );
            let data = (0..w * h)
                .map(|i| ((i * 7919 + c * 104_729) % 251) as f32 / 250.0)
                .collect();
            GrayImage {
                width: w,
                height: h,
                data,
            }
        })
        .collect();
    let mut runs = Vec::new();
    for run in 0..warmup + repeats {
        let (out, timings) = net.forward_timed(&images, &geometry, true)?;
        let mut row = CascadeRow::from(timings);
        if let Some(pick) = pick {
            let [coarse, _, fine] = out.stages;
            let index = read_values(fine.index, "index map")?;
            let spread = vec![0f32; index.len()];
            let start = std::time::Instant::now();
            let modes = omnimvs_net::estimator::coarse_modes(
                &coarse,
                pick.coarse_modes(),
                geometry.samplers[2].grid(),
            )?;
            pick.refine(&index, &spread, &modes, &geometry.samplers[2], &gray)?;
            row.pick = start.elapsed().as_secs_f64();
            row.total += row.pick;
        }
        if run >= warmup {
            runs.push(row);
        }
    }
    Ok(CascadeBenchReport {
        config: config.clone(),
        params,
        folded_batch_norm: fold_batch_norm,
        host_convs,
        pick: pick.is_some(),
        runs,
        peak_rss_bytes: peak_rss_bytes(),
    })
}
