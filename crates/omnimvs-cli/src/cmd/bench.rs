//! `omnimvs bench`: forward-pass time per stage, train-step time and peak memory of the
//! network on a compute backend.

use std::path::PathBuf;

use anyhow::{Context, Result};
use omnimvs_core::fs::write_atomic;
use omnimvs_net::bundled::{BundledModel, PickChoice};
use omnimvs_net::{Backend, Family, NetConfig};
use omnimvs_synth::rig::preset_rig;
use serde::Serialize;

use crate::args::{BACKEND_HELP, Preset, parse_backend, parse_output_file};
use crate::bench::{
    BenchReport, CascadeBenchReport, ForwardOptions, TrainStepReport, bench_cascade_forward,
    bench_cascade_train_step, bench_forward, bench_train_step,
};
use crate::weights::parse_pick;

/// Time the network's stages, a training step and peak memory on a compute backend.
///
/// Time the network on a compute backend: the forward pass per stage (features,
/// sweep, fusion, cost volume, softargmin; for the cascade features, coarse, half- and
/// full-resolution stages), a training step (forward, backward, optimiser update), and
/// peak memory. Random weights and inputs, a synthetic 220-degree lookup table (the
/// cascade: the published rig); warm-up runs are not measured. Compare with PyTorch on
/// the same machine: scripts/net_parity/bench_torch.py.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Network: tiny, paper or cascade.
    #[arg(long, value_enum, default_value_t = Preset::Tiny)]
    pub preset: Preset,
    /// A network configuration JSON (the file beside a weights file, e.g.
    /// models/omnimvs-cascade.json) to time instead of the preset's network.
    #[arg(long, conflicts_with = "preset")]
    pub config: Option<PathBuf>,
    #[arg(long, default_value = "cpu", value_parser = parse_backend, help = BACKEND_HELP)]
    pub backend: Backend,
    /// Measured forward passes.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Unmeasured forward passes (and training steps) before the measured ones.
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    /// Measured training steps; 0 skips the training step.
    #[arg(long, default_value_t = 3)]
    pub train_steps: usize,
    /// Keep the batch norms as separate layers instead of folding them into the
    /// convolutions.
    #[arg(long)]
    pub no_fold: bool,
    /// The convolutions through burn's backend instead of the host kernels that `infer`
    /// uses on the `cpu` backend (`omnimvs_net::hostconv`): the reference for a comparison.
    #[arg(long)]
    pub burn_convs: bool,
    /// Leave out the learnt pick after the cascade (`omnimvs_net::pick`), which `infer` runs
    /// after the bundled cascade; the bundled picks are timed on each pass's answer otherwise.
    #[arg(long, conflicts_with = "pick")]
    pub no_pick: bool,
    /// The pick timed, as `infer --pick`: `auto` (the default: the bundled ones, as `chain`),
    /// `single` (the bundled first pick alone), `chain` (the bundled two),
    /// `off` (none), or a pick's `.safetensors` instead of the bundled ones (another layout,
    /// say; several, comma-separated, run one after the other).
    #[arg(long, value_name = "auto|off|single|chain|FILE[,FILE]", default_value = "auto", value_parser = parse_pick)]
    pub pick: PickChoice,
    /// Where the sweep runs: the backend's best (host on CPU backends, device on GPUs).
    #[arg(long, value_enum, default_value_t = SweepPlace::Auto)]
    pub sweep: SweepPlace,
    /// Also write the measurements as JSON to this file.
    #[arg(long, value_parser = parse_output_file)]
    pub json: Option<PathBuf>,
}

/// Where the benchmark's sweep runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SweepPlace {
    /// Host on CPU backends, device on GPUs.
    Auto,
    /// The host kernel that skips invalid samples (features go to host memory and back).
    Host,
    /// A gather on the device through the lookup table's taps.
    Device,
}

#[derive(Serialize)]
struct Report {
    backend: String,
    preset: String,
    device_sweep: bool,
    forward: Forward,
    train_step: Option<TrainStepReport>,
}

#[derive(Serialize)]
#[serde(untagged)]
enum Forward {
    OmniMvs(BenchReport),
    Cascade(CascadeBenchReport),
}

pub fn run(args: &Args) -> Result<()> {
    let backend = args.backend;
    let device = backend.device()?;
    let (config, name) = match &args.config {
        Some(path) => (
            omnimvs_net::weights::read_config(path)
                .with_context(|| format!("--config {}", path.display()))?,
            path.display().to_string(),
        ),
        None => (args.preset.config(), args.preset.name().to_string()),
    };
    let device_sweep = match args.sweep {
        SweepPlace::Auto => backend.is_gpu(),
        SweepPlace::Host => false,
        SweepPlace::Device => true,
    };
    outln!(
        "network {name} (CH {}, N {}, {}x{} output, {} cameras of {}x{}), backend {backend}, sweep on the {}",
        config.channels,
        config.num_invdepth,
        config.out_height,
        config.out_width,
        config.num_cameras,
        config.input_width,
        config.input_height,
        if device_sweep { "device" } else { "host" },
    );
    let (forward, train_step) = if config.family == Family::Cascade {
        bench_cascade(args, &config, &device)?
    } else {
        bench_omnimvs(args, &config, device_sweep, &device)?
    };
    if backend.is_gpu() {
        outln!("(peak memory above is host RSS; GPU memory is not measured here)");
    }
    if let Some(path) = &args.json {
        let report = Report {
            backend: backend.to_string(),
            preset: name,
            device_sweep,
            forward,
            train_step,
        };
        let text = serde_json::to_string_pretty(&report)?;
        write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        outln!("wrote {}", path.display());
    }
    Ok(())
}

fn bench_omnimvs(
    args: &Args,
    config: &NetConfig,
    device_sweep: bool,
    device: &burn::tensor::Device,
) -> Result<(Forward, Option<TrainStepReport>)> {
    let options = ForwardOptions {
        warmup: args.warmup,
        repeats: args.repeats,
        fold_batch_norm: !args.no_fold,
        device_sweep,
        host_convs: !args.burn_convs && args.backend == Backend::Cpu,
    };
    let forward = bench_forward(config, &options, device).context("forward benchmark")?;
    print_stage_table(
        &[
            ("features", 9),
            ("sweep", 9),
            ("fusion", 9),
            ("cost", 9),
            ("softargmin", 10),
            ("total", 9),
        ],
        &forward.runs,
        forward.median().as_ref(),
        |r| vec![r.features, r.sweep, r.fusion, r.cost, r.softargmin, r.total],
    );
    print_peak("after the forward passes", forward.peak_rss_bytes);
    let train_step = train_steps(args, || {
        bench_train_step(config, args.warmup, args.train_steps, device)
    })?;
    Ok((Forward::OmniMvs(forward), train_step))
}

fn bench_cascade(
    args: &Args,
    config: &NetConfig,
    device: &burn::tensor::Device,
) -> Result<(Forward, Option<TrainStepReport>)> {
    let rig = preset_rig()?;
    let pick = if args.no_pick {
        None
    } else {
        args.pick
            .load(Some(BundledModel::Cascade))
            .with_context(|| format!("--pick {}", args.pick))?
    };
    let forward = bench_cascade_forward(
        config,
        &rig.rig,
        rig.min_depth_m,
        ForwardOptions {
            warmup: args.warmup,
            repeats: args.repeats,
            fold_batch_norm: !args.no_fold,
            device_sweep: args.backend.is_gpu(),
            host_convs: !args.burn_convs && args.backend == Backend::Cpu,
        },
        pick.as_ref(),
        device,
    )
    .context("forward benchmark")?;
    outln!(
        "{} parameters, batch norms {}, convolutions {}",
        forward.params,
        if forward.folded_batch_norm {
            "folded"
        } else {
            "as separate layers"
        },
        if forward.host_convs {
            "on the host"
        } else {
            "through burn"
        }
    );
    print_stage_table(
        &[
            ("features", 9),
            ("coarse", 9),
            ("half", 9),
            ("full", 9),
            ("pick", 9),
            ("total", 9),
        ],
        &forward.runs,
        forward.median().as_ref(),
        |r| vec![r.features, r.coarse, r.mid, r.fine, r.pick, r.total],
    );
    print_peak("after the forward passes", forward.peak_rss_bytes);
    let train_step = train_steps(args, || {
        bench_cascade_train_step(
            config,
            &rig.rig,
            rig.min_depth_m,
            args.warmup,
            args.train_steps,
            device,
        )
    })?;
    Ok((Forward::Cascade(forward), train_step))
}

/// Prints the forward passes' stage timings: a header of `columns` (name, width), a row per
/// run and one for the `median`, each row's `seconds` in its column's width.
fn print_stage_table<R>(
    columns: &[(&str, usize)],
    runs: &[R],
    median: Option<&R>,
    seconds: impl Fn(&R) -> Vec<f64>,
) {
    let mut header = format!("{:<8}", "forward");
    for (name, width) in columns {
        header += &format!(" {name:>width$}");
    }
    outln!("{header}");
    let rows = runs
        .iter()
        .map(|r| ("run", r))
        .chain(median.map(|m| ("median", m)));
    for (label, r) in rows {
        let mut line = format!("{label:<8}");
        for ((_, width), value) in columns.iter().zip(seconds(r)) {
            line += &format!(" {value:>w$.3}s", w = width - 1);
        }
        outln!("{line}");
    }
}

/// The train-step benchmark `bench` and its printed steps, when `--train-steps` asks for any.
fn train_steps(
    args: &Args,
    bench: impl FnOnce() -> Result<TrainStepReport>,
) -> Result<Option<TrainStepReport>> {
    if args.train_steps == 0 {
        return Ok(None);
    }
    let report = bench().context("train-step benchmark")?;
    print_steps(&report);
    Ok(Some(report))
}

fn print_steps(report: &TrainStepReport) {
    for (i, (seconds, loss)) in report.steps.iter().zip(&report.losses).enumerate() {
        outln!("train step {:>2}: {seconds:.3}s (loss {loss:.3})", i + 1);
    }
    if let Some(m) = report.median() {
        outln!("train step median {m:.3}s ({:.2} steps/s)", 1.0 / m);
    }
    print_peak("after the training steps", report.peak_rss_bytes);
}

fn print_peak(when: &str, bytes: Option<u64>) {
    if let Some(bytes) = bytes {
        outln!("peak RSS {when}: {} MiB", bytes / (1 << 20));
    }
}
