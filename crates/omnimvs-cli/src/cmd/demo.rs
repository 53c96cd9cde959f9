//! `omnimvs demo`: the whole pipeline on a bundled default, in one command.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use omnimvs_core::{ColourPlanes, GrayImage};
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::gt::GroundTruth;
use omnimvs_data::image_io::write_png_u8;
use omnimvs_data::{Dataset, DepthEstimate, DepthEstimator, FrameRange};
use omnimvs_eval::metrics::ProtocolMetrics;
use omnimvs_eval::output::evaluation::write_index_png;
use omnimvs_eval::output::pictures::{error_map, fisheye_strip, gray_to_rgb, label_rows};
use omnimvs_eval::output::{
    ConfidenceRun, DepthRun, EvalReport, Evaluation, FrameScene, MethodScores, protocol_tables,
    write_text,
};
use omnimvs_eval::ply::write_ply;
use omnimvs_net::bundled::PickChoice;
use omnimvs_net::{Backend, BundledModel, NetEstimator};
use omnimvs_stereo::{SgmEstimator, SgmParams};
use omnimvs_sweep::LutCache;
use omnimvs_synth::rig::preset_rig;
use omnimvs_synth::{DatasetWriter, SceneKind, Shard, SynthOptions};

use crate::args::Size;
use crate::cmd::{eval, infer, sgm};
use crate::weights::{Weights, apply_pick};

/// Run the whole pipeline on a rendered scene (no data needed) and print its metrics.
///
/// Run the pipeline end to end on a default that needs nothing but this
/// repository: render a few frames of a synthetic `things` scene with exact
/// ground truth for the published 4-camera rig, estimate 360-degree depth with
/// the classical method (ZNCC + SGM) and with the bundled networks (the default
/// cascade, then `tiny`); print the
/// paper's metrics tables (the reference's protocol, and with sky scored); write pictures (inputs, panorama, ground truth,
/// estimates, error maps) and a PLY point cloud. If the reference samples are beside the repository
/// (../shared/data/omnimvs-samples), the real itbt_sample frame 1 is
/// processed as well.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (created; existing demo files are replaced).
    #[arg(long, default_value = "demo-out")]
    pub out: PathBuf,
    /// Number of synthetic frames.
    #[arg(long, default_value_t = 2)]
    pub frames: u32,
    /// Seed of the synthetic scenes.
    #[arg(long, default_value_t = 2026)]
    pub seed: u64,
    /// Output grid, HEIGHTxWIDTH.
    #[arg(long, default_value = "160x640")]
    pub size: Size,
    /// Number of inverse-depth hypotheses for the classical method.
    #[arg(long, default_value_t = 192)]
    pub ndepth: usize,
    /// Folder of the reference samples (skipped when absent).
    #[arg(long, default_value = "../shared/data/omnimvs-samples")]
    pub samples: PathBuf,
}

/// A bundled network prepared for a dataset.
struct Network {
    weights: Weights,
    estimator: NetEstimator,
}

/// Every bundled network, the default first (the cascade answers at the full 160x640, `tiny`
/// at 32x128), prepared for `ds` on the CPU.
fn networks(ds: &Dataset) -> Result<Vec<Network>> {
    let device = Backend::Cpu.device()?;
    std::iter::once(BundledModel::DEFAULT)
        .chain(
            BundledModel::ALL
                .into_iter()
                .filter(|m| *m != BundledModel::DEFAULT),
        )
        .map(|model| {
            let weights = Weights::Bundled(model);
            let net = model.load(&device)?;
            let (estimator, status) = NetEstimator::new(
                net,
                ds,
                &LutCache::default_location(),
                device.clone(),
                false,
            )?;
            infer::report_cache(status);
            let estimator = apply_pick(&PickChoice::Auto, &weights, estimator)?;
            Ok(Network { weights, estimator })
        })
        .collect()
}

/// Renders `frames` synthetic `things` frames for the published rig into `dir`.
fn render(dir: &Path, frames: u32, seed: u64) -> Result<()> {
    let source = preset_rig()?;
    let range = FrameRange::inclusive(1, frames);
    let options = SynthOptions::new(SceneKind::Things, seed);
    let writer = DatasetWriter::create_with(dir, &source, &options, &range)?;
    let t0 = Instant::now();
    writer.run(&Shard::ALL.frames(&range), |_| {})?;
    outln!(
        "{}: {frames} frame(s) rendered in {:.1} s",
        dir.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

/// One frame's images and every method's estimate (the classical method's first).
struct FrameEstimates {
    images: Vec<GrayImage>,
    /// The colour images, when the frame's images are in colour.
    colour: Option<Vec<ColourPlanes>>,
    estimates: Vec<DepthEstimate>,
}

/// The classical method and every network on `frames` of `ds`, each once per frame, with
/// `omnimvs sgm`'s and `omnimvs infer`'s files in `out/<sgm>` and `out/<net_prefix>STEM`.
/// Returns, per frame, the images and every method's estimate.
fn estimate_all(
    ds: &Dataset,
    stereo: &SgmEstimator,
    networks: &[Network],
    frames: &[u32],
    sgm_dir: &Path,
    net_dir: impl Fn(&Weights) -> PathBuf,
) -> Result<Vec<FrameEstimates>> {
    outln!("{}", sgm::header(ds, stereo));
    let mut sgm_run = ConfidenceRun::new(sgm_dir, *stereo.spec())?;
    let mut net_runs = networks
        .iter()
        .map(|n| {
            let backend = Backend::Cpu;
            let settings = infer::settings(&ds.root, &n.weights, &n.estimator, &backend);
            Ok(DepthRun::new(
                &net_dir(&n.weights),
                "infer.json",
                &settings,
                true,
            )?)
        })
        .collect::<Result<Vec<_>>>()?;
    let mut all = Vec::new();
    for &f in frames {
        let (images, colour) = ds.read_frame_and_colour(f)?;
        let mut estimates = vec![sgm::frame(ds, stereo, &mut sgm_run, f, &images)?];
        for (n, run) in networks.iter().zip(&mut net_runs) {
            let est = n.estimator.estimate(&images)?;
            infer::frame(ds, &n.estimator, run, f, &images, colour.as_deref(), &est)?;
            estimates.push(est);
        }
        all.push(FrameEstimates {
            images,
            colour,
            estimates,
        });
    }
    sgm::finish(ds, stereo, sgm_run, sgm_dir)?;
    for ((n, run), dir) in networks
        .iter()
        .zip(net_runs)
        .zip(networks.iter().map(|n| net_dir(&n.weights)))
    {
        infer::finish(&n.estimator, run)?;
        outln!("wrote {} frames to {}", frames.len(), dir.display());
    }
    Ok(all)
}

pub fn run(args: &Args) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let t0 = Instant::now();
    let data_dir = args.out.join("things");
    outln!(
        "[1/5] rendering {} synthetic `things` frames (published rig, 4 x 768x800) into {}",
        args.frames,
        data_dir.display()
    );
    render(&data_dir, args.frames, args.seed)?;

    let (height, width) = (args.size.height, args.size.width);
    outln!(
        "[2/5] classical method (ZNCC + SGM) and bundled networks, {height}x{width}, N = {}",
        args.ndepth
    );
    let ds = Dataset::open(&data_dir)?;
    let spec = ds.sweep_spec(height, width, 45.0, args.ndepth)?;
    let masks = ds.masks()?;
    let stereo = SgmEstimator::new(&ds.rig, Some(masks.clone()), spec, SgmParams::default())?;
    let networks = networks(&ds)?;
    let frames: Vec<u32> = (1..=args.frames).collect();
    let estimates = estimate_all(
        &ds,
        &stereo,
        &networks,
        &frames,
        &args.out.join("sgm"),
        |w| args.out.join(format!("net_{}", w.stem())),
    )?;

    outln!("[3/5] metrics and pictures of the classical method at full size");
    let eval = Evaluation::new(&ds, &frames, spec)?;
    let mut sgm_metrics = Vec::new();
    for (k, &frame) in frames.iter().enumerate() {
        let frame_estimates = &estimates[k];
        let sgm = &frame_estimates.estimates[0];
        sgm_metrics.push(eval.score(k, sgm)?.1);
        let scene = FrameScene {
            rig: &ds.rig,
            images: &frame_estimates.images,
            masks: &masks,
            colour: frame_estimates.colour.as_deref(),
        };
        let path = args.out.join(format!("things_{frame:05}.png"));
        write_truth_comparison(&path, sgm, scene, &eval.truths[k].gt)?;
        outln!("  wrote {} and its point cloud", path.display());
    }
    let rows: Vec<(String, ProtocolMetrics)> = ProtocolMetrics::mean(&sgm_metrics)
        .map(|mean| (SgmEstimator::NAME.to_string(), mean))
        .into_iter()
        .collect();
    let table = protocol_tables(&rows);
    write_text(&args.out.join("metrics.md"), &table)?;

    outln!(
        "[4/5] bundled networks ({}) against the classical method, all scored at {height}x{width}, \
         N = {} (a coarser output upsampled)",
        networks
            .iter()
            .map(|n| n.weights.stem())
            .collect::<Vec<_>>()
            .join(", "),
        args.ndepth
    );
    let eval_dir = args.out.join("eval");
    let report = score_all(&eval, &networks, &estimates, &eval_dir)?;
    eval::report(&report, Some(&eval_dir))?;
    let net_table = report.table();

    let itbt = args.samples.join("itbt_sample");
    if itbt.join("config.yaml").is_file() {
        outln!("[5/5] real data: itbt_sample frame 1");
        let ds = Dataset::open(&itbt)?;
        let spec = ds.sweep_spec(height, width, 45.0, args.ndepth)?;
        let stereo = SgmEstimator::new(&ds.rig, Some(ds.masks()?), spec, SgmParams::default())?;
        let networks = self::networks(&ds)?;
        let sgm_dir = args.out.join("itbt_sgm");
        let net_dir = |w: &Weights| args.out.join(format!("itbt_net_{}", w.stem()));
        estimate_all(&ds, &stereo, &networks, &[1], &sgm_dir, net_dir)?;
        outln!(
            "  ZNCC+SGM: {}",
            sgm_dir.join("00001_invdepth.png").display()
        );
        for n in &networks {
            outln!(
                "  network `{}`: {}",
                n.weights.stem(),
                net_dir(&n.weights).join("00001_vis.png").display()
            );
        }
    } else {
        outln!(
            "[5/5] {} not found: skipping the real sample",
            itbt.display()
        );
    }
    outln!(
        "\nClassical method at {height}x{width}, N = {}, on {} synthetic frames (error in % of N; lower is better):\n\n{}",
        args.ndepth,
        args.frames,
        table.trim_end()
    );
    outln!(
        "\nNetwork and classical method at the same grid:\n\n{}",
        net_table.trim_end()
    );
    outln!(
        "\ndone in {:.1} s: pictures, point clouds and metrics in {}",
        t0.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

/// `things_%05d.png` (rows: inputs, panorama at the estimated depth, ground truth, the
/// estimate, its error) and the estimate's point cloud beside it (`_sgm.ply`).
fn write_truth_comparison(
    path: &Path,
    est: &DepthEstimate,
    scene: FrameScene<'_>,
    gt: &GroundTruth,
) -> Result<()> {
    let (grid, hyps) = (&est.spec.grid, &est.spec.hypotheses);
    let pano = scene.panorama(est)?;
    let gt_inv = est.spec.inv_depth_of(&gt.index);
    let max_inv = hyps.max_inv_depth();
    let rows: Vec<(String, Vec<u8>)> = vec![
        ("inputs".into(), fisheye_strip(scene.images, grid.width)),
        (
            "panorama at the estimated depth".into(),
            gray_to_rgb(&pano.image),
        ),
        (
            "ground truth".into(),
            colorize(&gt_inv, 0.0, max_inv, Colormap::Turbo, Some(&gt.valid)),
        ),
        (
            est.method.clone(),
            colorize(&est.inv_depth, 0.0, max_inv, Colormap::Turbo, None),
        ),
        (
            format!("{} error", est.method),
            error_map(&est.index, gt, est.spec.ndepth()),
        ),
    ];
    let (px, height) = label_rows(&rows, grid.width);
    write_png_u8(path, grid.width, height, 3, &px)?;
    let ply = path.with_file_name(format!(
        "{}_sgm.ply",
        path.file_stem().unwrap_or_default().to_string_lossy()
    ));
    write_ply(&ply, &scene.point_cloud(est, &pano)?)?;
    Ok(())
}

/// `omnimvs eval`'s report of the estimates in memory (the networks first, as `eval --method
/// net,sgm` orders them), with its pictures of the first frame in `dir`.
fn score_all(
    eval: &Evaluation,
    networks: &[Network],
    estimates: &[FrameEstimates],
    dir: &Path,
) -> Result<EvalReport> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let ndepth = eval.spec.ndepth();
    let gt = &eval.truths[0].gt;
    let first = eval.frames[0];
    write_index_png(
        &dir.join(format!("{first:05}_gt.png")),
        &gt.index,
        gt,
        ndepth,
        true,
    )?;
    // Row k of the report is method `order[k]` of the estimates (0: the classical method).
    let order = (1..=networks.len()).chain(std::iter::once(0));
    let mut results = Vec::new();
    for m in order {
        let (name, file) = match m {
            0 => (SgmEstimator::NAME.to_string(), "sgm".to_string()),
            _ => {
                let stem = networks[m - 1].weights.stem();
                let name = if networks.len() > 1 {
                    format!("net ({stem})")
                } else {
                    "net".into()
                };
                (name, format!("net_{stem}"))
            }
        };
        let mut scores = MethodScores::new(&name, estimates[0].estimates[m].spec);
        let mut seconds = 0.0;
        for (k, &f) in eval.frames.iter().enumerate() {
            let est = &estimates[k].estimates[m];
            let (index, metrics) = eval.score(k, est)?;
            if k == 0 {
                write_index_png(
                    &dir.join(format!("{f:05}_{file}.png")),
                    &index,
                    gt,
                    ndepth,
                    false,
                )?;
            }
            scores.push(f, metrics);
            seconds += est.seconds;
        }
        results.push(scores.finish(&eval.spec, seconds / eval.frames.len() as f64)?);
    }
    Ok(EvalReport::new(eval, results))
}
