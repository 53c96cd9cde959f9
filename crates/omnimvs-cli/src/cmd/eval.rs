//! `omnimvs eval`: the paper's table rows (`>1 >3 >5 MAE RMS`) of several methods on the
//! same frames, at the same resolution, side by side.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_data::Dataset;
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::gt::GroundTruth;
use omnimvs_data::image_io::write_png_u8;
use omnimvs_data::metrics::{Metrics, frame_metrics, mean_metrics};
use omnimvs_net::{NetConfig, NetEstimator};
use omnimvs_stereo::{SgmParams, SphericalStereo};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LutCache};
use serde::Serialize;

use crate::args::{BACKEND_HELP, Frames, Size, parse_backend};
use crate::weights::{BUNDLED, Weights};

/// Evaluate methods against ground truth with the paper's metrics: per pixel
/// E = |n_hat - n*| / N * 100 over valid pixels; the percentages of E > 1, 3, 5, the mean
/// (MAE) and root mean square (RMS), averaged over frames. Every method runs at the same
/// output grid and N (the network's, or --size/--ndepth); the ground truth (320x640,
/// +-90 deg), masked by the reference's invalid rule at full resolution, is sampled at that
/// grid's rays, as in `infer`, `sgm` and training. Prints a Markdown table and writes
/// OUT/eval.json and OUT/eval.md; with --pictures also colour-mapped inverse-depth PNGs of
/// the first frame.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder with ground truth.
    #[arg(long)]
    pub data: PathBuf,
    /// Methods, comma-separated: net, sgm.
    #[arg(long, value_delimiter = ',', default_value = "net,sgm")]
    pub method: Vec<String>,
    /// Network weights, comma-separated for several rows: `bundled` (the model compiled
    /// into the binary, the default), our .safetensors files or reference checkpoints.
    #[arg(long, value_delimiter = ',', default_value = BUNDLED, value_parser = Weights::parse)]
    pub weights: Vec<Weights>,
    /// Frames, A..B (inclusive) or a single frame.
    #[arg(long)]
    pub frames: Frames,
    /// Output grid HxW when no network sets it (default: the tiny preset's 32x128).
    #[arg(long)]
    pub size: Option<Size>,
    /// Number of hypotheses N when no network sets it (default: the tiny preset's 64).
    #[arg(long)]
    pub ndepth: Option<usize>,
    /// Output folder for eval.json / eval.md.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the first frame's colour-mapped inverse depth of every method and of the
    /// ground truth to OUT.
    #[arg(long)]
    pub pictures: bool,
    #[arg(long, default_value = "cpu", value_parser = parse_backend, help = BACKEND_HELP)]
    pub backend: omnimvs_net::Backend,
}

#[derive(Serialize)]
struct MethodResult {
    method: String,
    metrics: Metrics,
    per_frame: Vec<(u32, Metrics)>,
    seconds_per_frame: f64,
}

#[derive(Serialize)]
struct EvalReport {
    dataset: PathBuf,
    frames: Vec<u32>,
    height: usize,
    width: usize,
    ndepth: usize,
    methods: Vec<MethodResult>,
}

fn write_index_png(
    path: &Path,
    index: &[f32],
    gt: &GroundTruth,
    ndepth: usize,
    mask: bool,
) -> Result<()> {
    let valid = mask.then_some(gt.valid.as_slice());
    let rgb = colorize(index, 0.0, (ndepth - 1) as f64, Colormap::Turbo, valid);
    write_png_u8(path, gt.width, gt.height, 3, &rgb)?;
    Ok(())
}

pub fn run(args: &Args) -> Result<()> {
    let ds = Dataset::open(&args.data)?;
    let frames: Vec<u32> = args
        .frames
        .0
        .clone()
        .filter(|&f| ds.gt_path(f).is_some())
        .collect();
    if frames.is_empty() {
        bail!(
            "no frame of {:?} has ground truth in {}",
            args.frames.0,
            ds.root.display()
        );
    }
    let device = args.backend.device()?;
    // The grid: the first network's, else the options, else the tiny preset's.
    let mut nets = Vec::new();
    if args.method.iter().any(|m| m == "net") {
        for weights in &args.weights {
            nets.push((weights.clone(), weights.load_family("tiny", &device)?));
        }
    }
    let tiny = NetConfig::tiny();
    let (height, width, ndepth, phi_deg) = match nets.first() {
        Some((_, net)) => (
            net.config().out_height,
            net.config().out_width,
            net.config().num_invdepth,
            net.config().phi_deg,
        ),
        None => (
            args.size.map_or(tiny.out_height, |s| s.height),
            args.size.map_or(tiny.out_width, |s| s.width),
            args.ndepth.unwrap_or(tiny.num_invdepth),
            tiny.phi_deg,
        ),
    };
    let grid = EquirectGrid::new(height, width, phi_deg)?;
    let hyps: InvDepthHypotheses = ds.hypotheses(ndepth)?;
    let masks = ds.masks()?;
    // The same ground truth as `infer` and `sgm` (and training): the reference's invalid rule
    // at full resolution, sampled at the grid's rays.
    let mut gts = Vec::new();
    for &f in &frames {
        gts.push(
            ds.ground_truth(f, &grid, &hyps)?
                .context("ground truth vanished")?,
        );
    }
    if let Some(out) = &args.out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        if args.pictures {
            write_index_png(
                &out.join(format!("{:05}_gt.png", frames[0])),
                &gts[0].index,
                &gts[0],
                ndepth,
                true,
            )?;
        }
    }

    let mut methods = Vec::new();
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template(
        "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} frames",
    )?);
    let mut evaluate =
        |name: String, file: &str, run: &mut dyn FnMut(u32) -> Result<Vec<f32>>| -> Result<()> {
            bar.reset();
            bar.set_length(frames.len() as u64);
            bar.set_prefix(name.clone());
            let mut per_frame = Vec::new();
            let start = Instant::now();
            for (k, (&f, gt)) in frames.iter().zip(&gts).enumerate() {
                let index = run(f)?;
                if k == 0
                    && args.pictures
                    && let Some(out) = &args.out
                {
                    write_index_png(
                        &out.join(format!("{f:05}_{file}.png")),
                        &index,
                        gt,
                        ndepth,
                        false,
                    )?;
                }
                per_frame.push((f, frame_metrics(&index, gt, ndepth)?));
                bar.inc(1);
            }
            let seconds_per_frame = start.elapsed().as_secs_f64() / frames.len() as f64;
            let all: Vec<Metrics> = per_frame.iter().map(|p| p.1).collect();
            let metrics = mean_metrics(&all).context("no frame evaluated")?;
            methods.push(MethodResult {
                method: name,
                metrics,
                per_frame,
                seconds_per_frame,
            });
            Ok(())
        };
    for method in &args.method {
        match method.as_str() {
            "net" => {
                for (weights, net) in std::mem::take(&mut nets) {
                    let c = net.config().clone();
                    if (c.out_height, c.out_width, c.num_invdepth) != (height, width, ndepth) {
                        bail!(
                            "{weights}: output {}x{} N={} differs from the evaluation grid {height}x{width} N={ndepth}",
                            c.out_height,
                            c.out_width,
                            c.num_invdepth
                        );
                    }
                    let (inference, _) = NetEstimator::new(
                        net,
                        &ds,
                        &LutCache::default_location(),
                        device.clone(),
                        args.backend.is_gpu(),
                    )?;
                    let stem = weights.stem();
                    let name = if args.weights.len() > 1 {
                        format!("net ({stem})")
                    } else {
                        "net".into()
                    };
                    evaluate(name, &format!("net_{stem}"), &mut |f| {
                        let images = ds.read_frame(f)?;
                        Ok(inference.run(&images)?.index)
                    })?;
                }
            }
            "sgm" => {
                let stereo = SphericalStereo::new(&ds.rig, grid, hyps, SgmParams::default())?;
                evaluate("ZNCC+SGM".into(), "sgm", &mut |f| {
                    let images = ds.read_frame(f)?;
                    Ok(stereo.compute(&images, Some(&masks))?.index.index)
                })?;
            }
            other => bail!("--method {other}: expected net or sgm"),
        }
    }
    bar.finish_and_clear();

    let mut table = format!(
        "{} frames {}..{} ({} frames), {height}x{width}, N = {ndepth}\n\n{}\n",
        ds.root.display(),
        frames[0],
        frames[frames.len() - 1],
        frames.len(),
        Metrics::MARKDOWN_HEADER
    );
    for m in &methods {
        table.push_str(&m.metrics.markdown_row(&m.method));
        table.push('\n');
    }
    print!("{table}");
    for m in &methods {
        println!("{}: {:.3} s/frame", m.method, m.seconds_per_frame);
    }
    if let Some(out) = &args.out {
        let report = EvalReport {
            dataset: ds.root.clone(),
            frames: frames.clone(),
            height,
            width,
            ndepth,
            methods,
        };
        std::fs::write(
            out.join("eval.json"),
            serde_json::to_string_pretty(&report)? + "\n",
        )?;
        std::fs::write(out.join("eval.md"), &table)?;
        println!("wrote {}", out.join("eval.json").display());
    }
    Ok(())
}
