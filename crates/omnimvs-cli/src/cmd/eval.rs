//! `omnimvs eval`: the paper's table rows (`>1 >3 >5 MAE RMS`) of several methods on the
//! same frames, scored at one evaluation grid, side by side, under both protocols.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_camera::fs::write_atomic;
use omnimvs_data::FrameRange;
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::gt::GroundTruth;
use omnimvs_data::image_io::write_png_u8;
use omnimvs_data::metrics::{Metrics, Protocol, ProtocolMetrics, eval_metrics, index_on_eval_grid};
use omnimvs_net::NetEstimator;
use omnimvs_stereo::{SgmParams, SphericalStereo};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LutCache};
use serde::Serialize;

use crate::args::{BACKEND_HELP, Method, Preset, Size, parse_backend};
use crate::weights::{BUNDLED, Weights};

/// Evaluate methods against ground truth with the paper's metrics.
///
/// Per pixel
/// E = |n_hat - n*| / N * 100 over scored pixels; the percentages of E > 1, 3, 5, the mean
/// (MAE) and root mean square (RMS), averaged over frames. Every method runs at its own grid
/// (the bundled network at 32x128, N = 64; a cascade network at 160x640; SGM at the
/// evaluation grid); its output is turned into inverse depth with its own hypotheses,
/// resampled on the sphere to the evaluation grid (--size, default 160x640 over +-45 deg,
/// bilinear, longitude wrapping around) and scored as indices of the evaluation's N
/// (--ndepth, default 192), so that every row is scored on the same pixels. Two tables:
/// the `reference` protocol (the reference implementation's evalError, the paper's tables:
/// sky is not scored) and the `with-sky` protocol (sky scored as index 0, as training sees
/// it). The ground truth (320x640, +-90 deg) is cropped to the middle rows for 160x640, as
/// the reference does, or sampled at the grid's rays for other grids. Prints both tables
/// and writes OUT/eval.json and OUT/eval.md; with --pictures also colour-mapped
/// hypothesis-index PNGs of the first frame on the evaluation grid.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder with ground truth.
    #[arg(long)]
    pub data: PathBuf,
    /// Methods, comma-separated: net, sgm.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "net,sgm")]
    pub method: Vec<Method>,
    /// Network weights, comma-separated for several rows: `bundled` (the model compiled
    /// into the binary, the default), our .safetensors files or reference checkpoints.
    #[arg(long, value_delimiter = ',', default_value = BUNDLED, value_parser = Weights::parse)]
    pub weights: Vec<Weights>,
    /// Architecture sizes of a reference PyTorch checkpoint or `--weights random`: paper,
    /// tiny or cascade (our .safetensors files and the bundled models carry their own).
    #[arg(long, value_enum, default_value_t = Preset::Paper)]
    pub preset: Preset,
    /// Frames, A..B (inclusive) or a single frame.
    #[arg(long)]
    pub frames: FrameRange,
    /// Evaluation grid HxW: every output is resampled to it before it is scored; SGM runs
    /// at it.
    #[arg(long, default_value = "160x640")]
    pub size: Size,
    /// Number of hypotheses N of the evaluation (the unit of E); SGM sweeps as many.
    #[arg(long, default_value_t = 192)]
    pub ndepth: usize,
    /// Latitude range of the evaluation grid, +-degrees (every method's grid must cover the
    /// same range).
    #[arg(long, default_value_t = 45.0)]
    pub phi_deg: f64,
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

/// The grid and the number of hypotheses a method answers at.
#[derive(Clone, Copy, Debug, Serialize)]
struct NativeGrid {
    height: usize,
    width: usize,
    phi_deg: f64,
    ndepth: usize,
}

impl NativeGrid {
    fn of(grid: &EquirectGrid, hyps: &InvDepthHypotheses) -> Self {
        Self {
            height: grid.height,
            width: grid.width,
            phi_deg: grid.phi_deg,
            ndepth: hyps.count,
        }
    }
}

#[derive(Serialize)]
struct FrameScores {
    frame: u32,
    /// The `reference` protocol.
    metrics: Metrics,
    /// The `with-sky` protocol.
    metrics_with_sky: Metrics,
}

#[derive(Serialize)]
struct MethodResult {
    method: String,
    /// The grid the method answered at, before it was resampled to the evaluation grid.
    native: NativeGrid,
    /// Whether the output was resampled (another grid or another N than the evaluation's).
    resampled: bool,
    /// Mean over frames, `reference` protocol.
    metrics: Metrics,
    /// Mean over frames, `with-sky` protocol.
    metrics_with_sky: Metrics,
    per_frame: Vec<FrameScores>,
    seconds_per_frame: f64,
}

/// What each metrics field of the report holds.
#[derive(Serialize)]
struct ProtocolNames {
    metrics: String,
    metrics_with_sky: String,
}

#[derive(Serialize)]
struct EvalReport {
    dataset: PathBuf,
    frames: Vec<u32>,
    /// The evaluation grid every output is scored at.
    height: usize,
    width: usize,
    phi_deg: f64,
    ndepth: usize,
    /// The protocol of the `metrics` fields (the paper's).
    protocol: Protocol,
    protocols: ProtocolNames,
    methods: Vec<MethodResult>,
}

/// The heading of one protocol's table.
pub(crate) fn protocol_heading(protocol: Protocol) -> String {
    format!(
        "Protocol `{}` ({})",
        protocol.name(),
        protocol.description()
    )
}

/// One Markdown table per protocol (the `reference` one first), each row labelled.
pub(crate) fn protocol_tables(rows: &[(String, ProtocolMetrics)]) -> String {
    let mut text = String::new();
    for (k, protocol) in Protocol::ALL.into_iter().enumerate() {
        if k > 0 {
            text.push('\n');
        }
        text.push_str(&protocol_heading(protocol));
        text.push_str(":\n\n");
        text.push_str(Metrics::MARKDOWN_HEADER);
        text.push('\n');
        for (label, m) in rows {
            text.push_str(&m.get(protocol).markdown_row(label));
            text.push('\n');
        }
    }
    text
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

/// A method to evaluate: its row name, picture file stem, native grid and hypotheses, and
/// how it answers a frame (hypothesis indices on its native grid).
struct Row<'a> {
    name: String,
    file: String,
    grid: EquirectGrid,
    hyps: InvDepthHypotheses,
    run: Box<dyn FnMut(u32) -> Result<Vec<f32>> + 'a>,
}

pub fn run(args: &Args) -> Result<()> {
    let ds = crate::dataset::open_dataset(&args.data)?;
    let frames: Vec<u32> = args
        .frames
        .indices()
        .into_iter()
        .filter(|&f| ds.gt_path(f).is_some())
        .collect();
    if frames.is_empty() {
        bail!(
            "no frame of {} has ground truth in {}",
            args.frames,
            ds.root.display()
        );
    }
    let device = args.backend.device()?;
    let (height, width, ndepth) = (args.size.height, args.size.width, args.ndepth);
    let grid = EquirectGrid::new(height, width, args.phi_deg)?;
    let hyps: InvDepthHypotheses = ds.hypotheses(ndepth)?;
    let masks = ds.masks()?;
    // The ground truth of the evaluation grid, with its sky mask for the two protocols.
    let mut truths = Vec::new();
    for &f in &frames {
        truths.push(
            ds.eval_truth(f, &grid, &hyps)?
                .context("ground truth vanished")?,
        );
    }
    if let Some(out) = &args.out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        if args.pictures {
            write_index_png(
                &out.join(format!("{:05}_gt.png", frames[0])),
                &truths[0].gt.index,
                &truths[0].gt,
                ndepth,
                true,
            )?;
        }
    }

    let mut methods: Vec<Row<'_>> = Vec::new();
    for method in &args.method {
        match method {
            Method::Net => {
                for weights in &args.weights {
                    let net = weights.load_family(args.preset.name(), &device)?;
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
                    let ds = &ds;
                    methods.push(Row {
                        name,
                        file: format!("net_{stem}"),
                        grid: *inference.grid(),
                        hyps: *inference.hypotheses(),
                        run: Box::new(move |f| {
                            let images = ds.read_frame(f)?;
                            Ok(inference.run(&images)?.index)
                        }),
                    });
                }
            }
            Method::Sgm => {
                let stereo = SphericalStereo::new(&ds.rig, grid, hyps, SgmParams::default())?;
                let (ds, masks) = (&ds, &masks);
                methods.push(Row {
                    name: "ZNCC+SGM".into(),
                    file: "sgm".into(),
                    grid,
                    hyps,
                    run: Box::new(move |f| {
                        let images = ds.read_frame(f)?;
                        Ok(stereo.compute(&images, Some(masks))?.index.index)
                    }),
                });
            }
        }
    }

    let mut results = Vec::new();
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template(
        "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} frames",
    )?);
    for mut method in methods {
        bar.reset();
        bar.set_length(frames.len() as u64);
        bar.set_prefix(method.name.clone());
        let resampled = method.grid != grid || method.hyps != hyps;
        let mut per_frame = Vec::new();
        let start = Instant::now();
        for (k, (&f, truth)) in frames.iter().zip(&truths).enumerate() {
            let native = (method.run)(f).with_context(|| format!("{}: frame {f}", method.name))?;
            let index = index_on_eval_grid(&native, &method.grid, &method.hyps, &grid, &hyps)
                .with_context(|| format!("{}: frame {f}", method.name))?;
            if k == 0
                && args.pictures
                && let Some(out) = &args.out
            {
                write_index_png(
                    &out.join(format!("{f:05}_{}.png", method.file)),
                    &index,
                    &truth.gt,
                    ndepth,
                    false,
                )?;
            }
            let m = eval_metrics(&index, truth, ndepth)
                .with_context(|| format!("{}: frame {f}", method.name))?;
            per_frame.push(FrameScores {
                frame: f,
                metrics: m.reference,
                metrics_with_sky: m.with_sky,
            });
            bar.inc(1);
        }
        let seconds_per_frame = start.elapsed().as_secs_f64() / frames.len() as f64;
        let all: Vec<ProtocolMetrics> = per_frame
            .iter()
            .map(|p| ProtocolMetrics {
                reference: p.metrics,
                with_sky: p.metrics_with_sky,
            })
            .collect();
        let mean = ProtocolMetrics::mean(&all).context("no frame evaluated")?;
        results.push(MethodResult {
            method: method.name,
            native: NativeGrid::of(&method.grid, &method.hyps),
            resampled,
            metrics: mean.reference,
            metrics_with_sky: mean.with_sky,
            per_frame,
            seconds_per_frame,
        });
    }
    bar.finish_and_clear();

    let rows: Vec<(String, ProtocolMetrics)> = results
        .iter()
        .map(|m| {
            let n = &m.native;
            (
                format!(
                    "{}, native {}x{}, N = {}",
                    m.method, n.height, n.width, n.ndepth
                ),
                ProtocolMetrics {
                    reference: m.metrics,
                    with_sky: m.metrics_with_sky,
                },
            )
        })
        .collect();
    let table = format!(
        "{} frames {}..{} ({} frames), evaluation grid {height}x{width} (+-{} deg), N = {ndepth}; \
         each method at its own grid, resampled to this one\n\n{}",
        ds.root.display(),
        frames[0],
        frames[frames.len() - 1],
        frames.len(),
        args.phi_deg,
        protocol_tables(&rows)
    );
    out!("{table}");
    for m in &results {
        outln!("{}: {:.3} s/frame", m.method, m.seconds_per_frame);
    }
    if let Some(out) = &args.out {
        let report = EvalReport {
            dataset: ds.root.clone(),
            frames: frames.clone(),
            height,
            width,
            phi_deg: args.phi_deg,
            ndepth,
            protocol: Protocol::Reference,
            protocols: ProtocolNames {
                metrics: format!(
                    "{}: {}",
                    Protocol::Reference,
                    Protocol::Reference.description()
                ),
                metrics_with_sky: format!(
                    "{}: {}",
                    Protocol::WithSky,
                    Protocol::WithSky.description()
                ),
            },
            methods: results,
        };
        let json = out.join("eval.json");
        write_atomic(
            &json,
            (serde_json::to_string_pretty(&report)? + "\n").as_bytes(),
        )
        .with_context(|| format!("writing {}", json.display()))?;
        let md = out.join("eval.md");
        write_atomic(&md, table.as_bytes()).with_context(|| format!("writing {}", md.display()))?;
        outln!("wrote {}", json.display());
    }
    Ok(())
}
