//! `omnimvs parity`: the same network on the same frame on several backends, compared.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail, ensure};
use omnimvs_core::fs::write_atomic;
use omnimvs_data::Dataset;
use omnimvs_net::Backend;
use omnimvs_net::infer::Inference;
use omnimvs_sweep::LutCache;
use serde::Serialize;

use crate::args::{Preset, parse_backend, parse_output_file};
use crate::weights::Weights;

/// Check that compute backends give the same network output on a real frame.
///
/// Check that compute backends agree: run the same weights on the same frame on every
/// backend of --backends, with the sweep on the host and on the device, and report the
/// largest difference of the hypothesis index (0..N-1) from the first backend's host-sweep
/// result. Exits non-zero when a difference exceeds --tolerance. With `--weights random`
/// one random network (drawn on the CPU) is loaded on every backend.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder (or its config.yaml).
    pub dataset: PathBuf,
    /// Frame to run.
    #[arg(long, default_value_t = 1)]
    pub frame: u32,
    /// Backends, comma-separated; the first is the reference, e.g. cpu,wgpu or
    /// cpu,libtorch-cuda:0.
    #[arg(long, value_delimiter = ',', value_parser = parse_backend, required = true)]
    pub backends: Vec<Backend>,
    /// Weights of the paper's network family (this checks its host and device sweep
    /// backends): `tiny` (the default, the bundled small one), a weights file, or `random` (a
    /// --preset network). The bundled default of `infer`, the cascade, is not of this family.
    #[arg(long, default_value = "tiny", value_parser = Weights::parse)]
    pub weights: Weights,
    /// Architecture sizes for a PyTorch checkpoint or `--weights random`: paper or tiny.
    #[arg(long, value_enum, default_value_t = Preset::Paper)]
    pub preset: Preset,
    /// Multiply the final cost by this factor on every backend (a softmax temperature): a
    /// random network's softargmin is nearly flat, and 100 or so makes it as structured as a
    /// trained one's, so that kernel differences show.
    #[arg(long, default_value_t = 1.0)]
    pub cost_scale: f32,
    /// Largest index difference allowed.
    #[arg(long, default_value_t = 1e-3)]
    pub tolerance: f32,
    /// Also write the comparison as JSON to this file.
    #[arg(long, value_parser = parse_output_file)]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Serialize)]
struct Row {
    backend: String,
    device_sweep: bool,
    seconds: f64,
    max_abs_diff: f32,
    mean_abs_diff: f32,
}

#[derive(Debug, Serialize)]
struct Report {
    dataset: PathBuf,
    frame: u32,
    weights: Weights,
    cost_scale: f32,
    height: usize,
    width: usize,
    num_invdepth: usize,
    /// Max minus min of the reference index map (a flat map would prove little).
    reference_spread: f32,
    tolerance: f32,
    rows: Vec<Row>,
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    let ds = datasets.open(&args.dataset)?;
    let images = ds
        .read_frame(args.frame)
        .with_context(|| format!("frame {}", args.frame))?;
    // Random weights are drawn once, on the CPU, and every backend loads that file.
    let scratch = tempdir_for_random(&args.weights)?;
    let result = (|| {
        let weights = match &scratch {
            Some(dir) => {
                let net = Weights::Random.load(args.preset.name(), &Backend::Cpu.device()?)?;
                let path = dir.join("random.safetensors");
                omnimvs_net::weights::save(&net, &path)?;
                Weights::File(path)
            }
            None => args.weights.clone(),
        };
        compare(args, &ds, &images, &weights)
    })();
    if let Some(dir) = scratch {
        let _ = std::fs::remove_dir_all(dir);
    }
    let report = result?;
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&report)? + "\n";
        write_atomic(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let worst = report
        .rows
        .iter()
        .map(|r| r.max_abs_diff)
        .fold(0.0f32, f32::max);
    if worst > args.tolerance {
        bail!(
            "backends disagree: max |index difference| {worst:.3e} exceeds the tolerance {:.1e}",
            args.tolerance
        );
    }
    outln!(
        "all backends agree within {:.1e} (worst {worst:.2e})",
        args.tolerance
    );
    Ok(())
}

fn tempdir_for_random(weights: &Weights) -> Result<Option<PathBuf>> {
    if *weights != Weights::Random {
        return Ok(None);
    }
    let dir = std::env::temp_dir().join(format!("omnimvs-parity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    Ok(Some(dir))
}

fn compare(
    args: &Args,
    ds: &Dataset,
    images: &[omnimvs_core::GrayImage],
    weights: &Weights,
) -> Result<Report> {
    let cache = LutCache::default_location();
    let mut reference: Option<Vec<f32>> = None;
    let mut rows = Vec::new();
    let mut shape = (0, 0, 0);
    outln!(
        "{:<18} {:<7} {:>9} {:>13} {:>13}",
        "backend",
        "sweep",
        "seconds",
        "max |diff|",
        "mean |diff|"
    );
    for &backend in &args.backends {
        let device = backend.device()?;
        let mut net = weights.load(args.preset.name(), &device)?.fold_batch_norm();
        if args.cost_scale != 1.0 {
            net = net.scale_cost(args.cost_scale);
        }
        let (mut inference, _) = Inference::new(net, ds, &cache, device)?;
        for device_sweep in [false, true] {
            if device_sweep {
                inference.sweep_on_device();
            }
            let start = Instant::now();
            let result = inference
                .run(images)
                .with_context(|| format!("frame {} on {backend}", args.frame))?;
            let seconds = start.elapsed().as_secs_f64();
            let reference = reference.get_or_insert_with(|| {
                shape = (
                    result.spec.height(),
                    result.spec.width(),
                    result.spec.ndepth(),
                );
                result.index.clone()
            });
            ensure!(
                result.index.len() == reference.len(),
                "{backend}: {} outputs, the reference has {}",
                result.index.len(),
                reference.len()
            );
            let diffs: Vec<f32> = result
                .index
                .iter()
                .zip(reference.iter())
                .map(|(a, b)| (a - b).abs())
                .collect();
            // A NaN anywhere must fail the check, so it counts as infinitely far.
            let max_abs_diff = diffs
                .iter()
                .map(|d| if d.is_nan() { f32::INFINITY } else { *d })
                .fold(0.0f32, f32::max);
            let mean_abs_diff = diffs.iter().sum::<f32>() / diffs.len().max(1) as f32;
            let sweep = if device_sweep { "device" } else { "host" };
            outln!(
                "{:<18} {sweep:<7} {seconds:>8.3}s {max_abs_diff:>13.3e} {mean_abs_diff:>13.3e}",
                backend.to_string()
            );
            rows.push(Row {
                backend: backend.to_string(),
                device_sweep,
                seconds,
                max_abs_diff,
                mean_abs_diff,
            });
        }
    }
    let reference = reference.unwrap_or_default();
    let spread = reference.iter().copied().fold(f32::MIN, f32::max)
        - reference.iter().copied().fold(f32::MAX, f32::min);
    outln!(
        "reference: {} (host sweep), {}x{} output, N = {}, index spread {spread:.2}",
        args.backends[0],
        shape.0,
        shape.1,
        shape.2
    );
    if spread < 1.0 {
        eprintln!(
            "warning: the reference map is nearly flat (index spread {spread:.2}), which hides \
             kernel differences; sharpen it with --cost-scale (e.g. 100)"
        );
    }
    Ok(Report {
        dataset: args.dataset.clone(),
        frame: args.frame,
        weights: args.weights.clone(),
        cost_scale: args.cost_scale,
        height: shape.0,
        width: shape.1,
        num_invdepth: shape.2,
        reference_spread: spread,
        tolerance: args.tolerance,
        rows,
    })
}
