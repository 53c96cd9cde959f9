//! `omnimvs sgm`: the classical method (spherical-sweep ZNCC + SGM) on the
//! frames of a dataset.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use omnimvs_camera::fs::write_atomic;
use omnimvs_data::FrameRange;
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::gt::write_f32_tiff;
use omnimvs_data::image_io::write_png_u8;
use omnimvs_data::metrics::{Metrics, Protocol, ProtocolMetrics, eval_metrics};
use omnimvs_stereo::{
    DEFAULT_P1, DEFAULT_P2, Directions, SgmParams, SphericalStereo, StageTimings, SweepStep,
};
use omnimvs_sweep::EquirectGrid;
use serde::Serialize;

use crate::args::Size;
use crate::cmd::eval::protocol_tables;

/// Depth by the classical method, ZNCC + SGM (no network, no GPU).
///
/// Depth by the classical method of the paper's Table 3 ("ZNCC+SGM"):
/// every camera's gray image is swept over N spheres, 9x9 ZNCC between all
/// camera pairs that see a point gives the matching cost, and semi-global
/// matching (8 paths wrapping round in longitude) regularises it. No weights,
/// no GPU.
///
/// Writes per frame, in OUT: %05d.tiff (f32 inverse depth, 1/m),
/// %05d_index.tiff (f32 hypothesis index), %05d_invdepth.png (colour map,
/// near = warm, scaled to the frame's 1st..99th percentile),
/// %05d_confidence.png/.tiff (1 - best/second-best aggregated cost); and
/// sgm.json (the parameters, timings and, when the dataset has ground
/// truth, the per-frame metrics and their mean, also in metrics.md). Metrics
/// follow the `reference` protocol (the reference's evalError, the paper's
/// tables: sky is not scored), with the `with-sky` protocol (sky scored as
/// index 0) beside them.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder (or its config.yaml).
    pub dataset: PathBuf,
    /// Frames, A..B (inclusive) or a single frame (default: all frames found).
    #[arg(long)]
    pub frames: Option<FrameRange>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Output grid, HEIGHTxWIDTH.
    #[arg(long, default_value = "160x640")]
    pub size: Size,
    /// Latitude range of the output, +-degrees.
    #[arg(long, default_value_t = 45.0)]
    pub phi_deg: f64,
    /// Number of inverse-depth hypotheses N (even).
    #[arg(long, default_value_t = 192)]
    pub ndepth: usize,
    /// SGM penalty for a change of one hypothesis, in matching-cost units
    /// ((1 - zncc) / 2, in [0, 1]).
    #[arg(long, default_value_t = DEFAULT_P1)]
    pub p1: f32,
    /// SGM penalty for larger jumps, same units (>= P1).
    #[arg(long, default_value_t = DEFAULT_P2)]
    pub p2: f32,
    /// Aggregate along 4 paths instead of 8.
    #[arg(long)]
    pub four_paths: bool,
    /// Match on every other sphere only (about half the time; odd
    /// hypotheses interpolated).
    #[arg(long)]
    pub every_other: bool,
}

#[derive(Serialize)]
struct FrameRecord {
    frame: u32,
    timings: StageTimings,
    /// Inverse depths (1/m) at the ends of the colour map.
    color_range: [f32; 2],
    mean_confidence: f32,
    /// The `reference` protocol.
    metrics: Option<Metrics>,
    /// The `with-sky` protocol.
    metrics_with_sky: Option<Metrics>,
}

#[derive(Serialize)]
struct Summary<'a> {
    method: &'static str,
    dataset: String,
    height: usize,
    width: usize,
    phi_deg: f64,
    ndepth: usize,
    min_depth_m: f64,
    params: SgmParams,
    /// The protocol of the `metrics` fields; `metrics_with_sky` scores sky too.
    protocol: Protocol,
    frames: &'a [FrameRecord],
    mean_metrics: Option<Metrics>,
    mean_metrics_with_sky: Option<Metrics>,
}

/// The `q`-quantile of the finite values.
fn quantile(values: &[f32], q: f64) -> f32 {
    let mut v: Vec<f32> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

pub fn run(args: &Args) -> Result<()> {
    let ds = crate::dataset::open_dataset(&args.dataset)?;
    let frames: Vec<u32> = match &args.frames {
        Some(range) => range.indices(),
        None => ds.frames_found(),
    };
    if frames.is_empty() {
        bail!("{}: no frame found", ds.root.display());
    }
    let (h, w) = (args.size.height, args.size.width);
    let grid = EquirectGrid::new(h, w, args.phi_deg)?;
    let hyps = ds.hypotheses(args.ndepth)?;
    let params = SgmParams {
        p1: args.p1,
        p2: args.p2,
        directions: if args.four_paths {
            Directions::Four
        } else {
            Directions::Eight
        },
        sweep: if args.every_other {
            SweepStep::EveryOther
        } else {
            SweepStep::All
        },
        ..SgmParams::default()
    };
    let stereo = SphericalStereo::new(&ds.rig, grid, hyps, params)?;
    let masks = ds.masks()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    outln!(
        "ZNCC+SGM: {} cameras, {h}x{w} (+-{} deg), N = {}, min depth {} m, P1 = {}, P2 = {}, {} paths, {:?} spheres",
        ds.rig.len(),
        args.phi_deg,
        args.ndepth,
        ds.config.min_depth_m,
        params.p1,
        params.p2,
        params.directions.count(),
        params.sweep
    );
    let mut records = Vec::new();
    for &frame in &frames {
        let images = ds.read_frame(frame)?;
        let out = stereo.compute(&images, Some(&masks))?;
        let stem = args.out.join(format!("{frame:05}"));
        let path = |suffix: &str| PathBuf::from(format!("{}{suffix}", stem.display()));
        write_f32_tiff(&path(".tiff"), w, h, &out.inv_depth)?;
        write_f32_tiff(&path("_index.tiff"), w, h, &out.index.index)?;
        let lo = quantile(&out.inv_depth, 0.01);
        let hi = quantile(&out.inv_depth, 0.99);
        let rgb = colorize(
            &out.inv_depth,
            f64::from(lo),
            f64::from(hi),
            Colormap::Turbo,
            None,
        );
        write_png_u8(&path("_invdepth.png"), w, h, 3, &rgb)?;
        let conf = &out.index.confidence;
        write_f32_tiff(&path("_confidence.tiff"), w, h, conf)?;
        let gray: Vec<u8> = conf
            .iter()
            .map(|&c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect();
        write_png_u8(&path("_confidence.png"), w, h, 1, &gray)?;
        let metrics = match ds.eval_truth(frame, &grid, &hyps) {
            Ok(Some(truth)) => Some(eval_metrics(&out.index.index, &truth, args.ndepth)?),
            Ok(None) => None,
            Err(e) => {
                eprintln!("frame {frame}: no metrics: {e}");
                None
            }
        };
        let t = out.timings;
        outln!(
            "frame {frame:5}: warp {:.2} s, cost {:.2} s, aggregation {:.2} s, wta {:.2} s, total {:.2} s{}",
            t.warp_s,
            t.cost_s,
            t.aggregation_s,
            t.wta_s,
            t.total_s,
            metrics.map_or(String::new(), |m| {
                let (r, s) = (m.reference, m.with_sky);
                format!(
                    "; >1 {:.2}% >3 {:.2}% >5 {:.2}% MAE {:.2} RMS {:.2} (with sky: MAE {:.2} RMS {:.2})",
                    r.over1_pct, r.over3_pct, r.over5_pct, r.mae, r.rms, s.mae, s.rms
                )
            })
        );
        records.push(FrameRecord {
            frame,
            timings: t,
            color_range: [lo, hi],
            mean_confidence: conf.iter().sum::<f32>() / conf.len() as f32,
            metrics: metrics.map(|m| m.reference),
            metrics_with_sky: metrics.map(|m| m.with_sky),
        });
    }
    let per_frame: Vec<(u32, ProtocolMetrics)> = records
        .iter()
        .filter_map(|r| {
            Some((
                r.frame,
                ProtocolMetrics {
                    reference: r.metrics?,
                    with_sky: r.metrics_with_sky?,
                },
            ))
        })
        .collect();
    let all: Vec<ProtocolMetrics> = per_frame.iter().map(|(_, m)| *m).collect();
    let mean = ProtocolMetrics::mean(&all);
    if let Some(m) = mean {
        let mut rows: Vec<(String, ProtocolMetrics)> = per_frame
            .iter()
            .map(|(f, fm)| (format!("frame {f}"), *fm))
            .collect();
        rows.push(("ZNCC+SGM (mean)".into(), m));
        let table = format!(
            "{} ({} frames with ground truth), {h}x{w}, N = {}\n\n{}",
            ds.root.display(),
            per_frame.len(),
            args.ndepth,
            protocol_tables(&rows)
        );
        out!("{table}");
        let md = args.out.join("metrics.md");
        write_atomic(&md, table.as_bytes()).with_context(|| format!("writing {}", md.display()))?;
    }
    let summary = Summary {
        method: "ZNCC+SGM",
        dataset: ds.root.display().to_string(),
        height: h,
        width: w,
        phi_deg: args.phi_deg,
        ndepth: args.ndepth,
        min_depth_m: ds.config.min_depth_m,
        params,
        protocol: Protocol::Reference,
        frames: &records,
        mean_metrics: mean.map(|m| m.reference),
        mean_metrics_with_sky: mean.map(|m| m.with_sky),
    };
    let json = args.out.join("sgm.json");
    write_atomic(&json, serde_json::to_string_pretty(&summary)?.as_bytes())
        .with_context(|| format!("writing {}", json.display()))?;
    outln!("wrote {} frames to {}", records.len(), args.out.display());
    Ok(())
}
