//! `omnimvs eval`: the paper's table rows (`>1 >3 >5 MAE RMS`) of several methods on the
//! same frames, scored at one evaluation grid, side by side, under both protocols.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_data::{Dataset, DepthEstimator, FrameRange, Speed};
use omnimvs_eval::output::evaluation::write_index_png;
use omnimvs_eval::output::{EvalReport, Evaluation, MethodScores};
use omnimvs_eval::photometric::{PhotometricReport, PhotometricRow, photometric_difference};
use omnimvs_net::NetEstimator;
use omnimvs_net::bundled::PickChoice;
use omnimvs_stereo::{SgmEstimator, SgmParams};
use omnimvs_sweep::{LutCache, SweepSpec};

use crate::args::{BACKEND_HELP, Method, Preset, SweepArgs, parse_backend};
use crate::cmd::infer::{InputSize, input_size, speed_input_size, speed_pick};
use crate::weights::{BUNDLED, Weights, apply_pick, parse_pick};

/// Evaluate methods against ground truth with the paper's metrics.
///
/// Per pixel
/// E = |n_hat - n*| / N * 100 over scored pixels; the percentages of E > 1, 3, 5, the mean
/// (MAE) and root mean square (RMS), averaged over frames. Every method runs at its own grid
/// (the bundled cascade at 160x640, N = 192; the bundled `tiny` at 32x128, N = 64; SGM at the
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
    /// Network weights, comma-separated for several rows: `bundled` (the default: the
    /// cascade compiled into the binary, 160x640, N = 192), a bundled model by name
    /// (`cascade`, `tiny`: the paper's network, small, 32x128, N = 64), our .safetensors files
    /// or reference checkpoints.
    #[arg(long, value_delimiter = ',', default_value = BUNDLED, value_parser = Weights::parse)]
    pub weights: Vec<Weights>,
    /// Architecture sizes of a reference PyTorch checkpoint or `--weights random`: paper,
    /// tiny or cascade (our .safetensors files and the bundled models carry their own).
    #[arg(long, value_enum, default_value_t = Preset::Paper)]
    pub preset: Preset,
    /// The learnt pick after the cascade, as `infer --pick`: `auto` (the bundled cascade's own
    /// after the bundled cascade: its two picks in turn), `off`, `single` (the bundled first
    /// pick alone), `chain` (the bundled pick and the second one after it), or a pick's
    /// .safetensors (after every cascade row; several, comma-separated, run one after the
    /// other).
    #[arg(long, value_name = "auto|off|single|chain|FILE[,FILE]", default_value = "auto", value_parser = parse_pick)]
    pub pick: PickChoice,
    /// Frames, A..B (inclusive) or a single frame.
    #[arg(long)]
    pub frames: FrameRange,
    /// Size the images are fed to the networks at, as `infer --input-size`: `model`, `native`,
    /// `angular` or HEIGHTxWIDTH.
    #[arg(long)]
    pub input_size: Option<InputSize>,
    /// Speed preset of every row, as `sgm --speed` and `infer --speed`: ZNCC+SGM over its
    /// preset's spheres (scored in the evaluation's N), the network at its preset's input size
    /// and picks. Instead of --input-size and --pick.
    #[arg(long, conflicts_with_all = ["input_size", "pick"])]
    pub speed: Option<Speed>,
    /// Output grid and hypotheses.
    #[command(flatten)]
    pub sweep: SweepArgs,
    /// Output folder for eval.json / eval.md.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the first frame's colour-mapped inverse depth of every method and of the
    /// ground truth to OUT.
    #[arg(long)]
    pub pictures: bool,
    /// Score how well each method's depth explains the images instead of comparing it with
    /// ground truth: the cross-camera photometric difference (every output point projected into
    /// the cameras that see it; the median gray difference over camera pairs divided by the
    /// gray values' standard deviation; lower is better), beside a constant depth of 3 m as a
    /// floor. What `eval` does on frames without ground truth (real recordings).
    #[arg(long)]
    pub photometric: bool,
    #[arg(long, default_value = "cpu", value_parser = parse_backend, help = BACKEND_HELP)]
    pub backend: omnimvs_net::Backend,
}

/// A method to evaluate: its row name, picture file stem and estimator.
pub struct Row {
    pub name: String,
    pub file: String,
    pub estimator: Box<dyn DepthEstimator>,
}

/// The network rows of `weights` (named `net`, or `net (STEM)` when there are several) and
/// the classical method's at the evaluation sweep, in the order of `methods`; each cascade
/// row with the learnt pick `pick` gives it.
///
/// # Errors
/// Weights that cannot be loaded or a rig that does not fit a method.
#[allow(clippy::too_many_arguments)]
pub fn rows(
    ds: &Dataset,
    methods: &[Method],
    weights: &[Weights],
    pick: &PickChoice,
    preset: Preset,
    input: Option<InputSize>,
    speed: Option<Speed>,
    backend: &omnimvs_net::Backend,
    spec: SweepSpec,
) -> Result<Vec<Row>> {
    let pick = &speed_pick(speed, pick);
    let device = backend.device()?;
    let mut rows: Vec<Row> = Vec::new();
    for method in methods {
        match method {
            Method::Net => {
                for w in weights {
                    let mut net = w.load_family(preset.name(), &device)?;
                    let model_size = [net.config().input_height, net.config().input_width];
                    let input = speed_input_size(speed, input, model_size);
                    if let Some(size) = input_size(input, w, model_size, ds)? {
                        net.set_input_size(size)
                            .with_context(|| format!("--input-size {}x{}", size[0], size[1]))?;
                    }
                    let (estimator, _) = NetEstimator::new(
                        net,
                        ds,
                        &LutCache::default_location(),
                        device.clone(),
                        backend.is_gpu(),
                    )?;
                    let estimator = apply_pick(pick, w, estimator)?;
                    let stem = w.stem();
                    rows.push(Row {
                        name: if weights.len() > 1 {
                            format!("net ({stem})")
                        } else {
                            "net".into()
                        },
                        file: format!("net_{stem}"),
                        estimator: Box::new(estimator),
                    });
                }
            }
            Method::Sgm => rows.push(Row {
                name: SgmEstimator::NAME.into(),
                file: "sgm".into(),
                estimator: Box::new(SgmEstimator::new(
                    &ds.rig,
                    Some(ds.masks()?),
                    match speed {
                        Some(speed) => ds.sweep_spec(
                            spec.height(),
                            spec.width(),
                            spec.grid.phi_deg,
                            speed.sgm_ndepth(),
                        )?,
                        None => spec,
                    },
                    SgmParams::default(),
                )?),
            }),
            Method::Mccnn | Method::Sweepnet => {
                let (cost, file) = if *method == Method::Mccnn {
                    (crate::args::Cost::Mccnn, "mccnn")
                } else {
                    (crate::args::Cost::Sweepnet, "sweepnet")
                };
                let estimator =
                    crate::cmd::sgm::estimator(ds, spec, cost, "bundled", |(p1, p2)| SgmParams {
                        p1,
                        p2,
                        ..SgmParams::default()
                    })?;
                rows.push(Row {
                    name: estimator.name().into(),
                    file: file.into(),
                    estimator: Box::new(estimator),
                });
            }
        }
    }
    Ok(rows)
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    let ds = datasets.open(&args.data)?;
    let with_truth = args
        .frames
        .indices()
        .into_iter()
        .any(|f| ds.gt_path(f).is_some());
    if args.photometric || !with_truth {
        return photometric(args, &ds);
    }
    let frames = frames_with_truth(&ds, args.frames)?;
    let spec = args.sweep.spec(&ds)?;
    let pictures = match &args.out {
        Some(out) => {
            std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
            args.pictures.then_some(out.as_path())
        }
        None => None,
    };
    let rows = args.rows(&ds, spec)?;
    let evaluation = evaluate(&ds, &frames, spec, rows, pictures)?;
    report(&evaluation, args.out.as_deref())
}

impl Args {
    /// The rows these options ask for on `ds`, scored at `spec`.
    ///
    /// # Errors
    /// As [`rows`].
    fn rows(&self, ds: &Dataset, spec: SweepSpec) -> Result<Vec<Row>> {
        rows(
            ds,
            &self.method,
            &self.weights,
            &self.pick,
            self.preset,
            self.input_size,
            self.speed,
            &self.backend,
            spec,
        )
    }
}

/// A progress bar over frames, named by its prefix.
fn frames_bar() -> Result<ProgressBar> {
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template(
        "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} frames",
    )?);
    Ok(bar)
}

/// The constant depth of the photometric evaluation's floor row, metres.
const FLOOR_DEPTH_M: f32 = 3.0;

/// `eval --photometric`, and `eval` on frames without ground truth: every method's
/// cross-camera photometric difference, frame by frame, beside a constant depth.
fn photometric(args: &Args, ds: &Dataset) -> Result<()> {
    let found = ds.frames_found();
    let frames: Vec<u32> = args
        .frames
        .indices()
        .into_iter()
        .filter(|f| found.contains(f))
        .collect();
    if frames.is_empty() {
        bail!(
            "no frame of {} has images in {}",
            args.frames,
            ds.root.display()
        );
    }
    let spec = args.sweep.spec(ds)?;
    let rows = args.rows(ds, spec)?;
    // Each frame read once for every row and the constant depth.
    let floor = vec![1.0 / FLOOR_DEPTH_M; spec.grid.height * spec.grid.width];
    let mut values = vec![Vec::new(); rows.len() + 1];
    let mut seconds = vec![0.0; rows.len()];
    let bar = frames_bar()?;
    bar.set_length(frames.len() as u64);
    bar.set_prefix("photometric");
    for &f in &frames {
        let images = ds.read_frame(f).with_context(|| format!("frame {f}"))?;
        for (k, row) in rows.iter().enumerate() {
            let start = Instant::now();
            let est = row
                .estimator
                .estimate(&images)
                .with_context(|| format!("{}: frame {f}", row.name))?;
            seconds[k] += start.elapsed().as_secs_f64();
            let value = photometric_difference(&ds.rig, &images, &est.spec.grid, &est.inv_depth);
            values[k].push((f, value));
        }
        values[rows.len()].push((
            f,
            photometric_difference(&ds.rig, &images, &spec.grid, &floor),
        ));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let per_frame = |s: f64| s / frames.len() as f64;
    let names = rows
        .iter()
        .map(|row| row.name.clone())
        .chain([format!("a constant {FLOOR_DEPTH_M} m")]);
    let results = names
        .zip(values)
        .zip(seconds.into_iter().chain([0.0]))
        .map(|((name, values), s)| PhotometricRow::new(name, values, per_frame(s)))
        .collect();
    let report = PhotometricReport::new(&ds.root, frames, results);
    out!("{}", report.table());
    if let Some(out) = &args.out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        report.write(out)?;
        outln!("wrote {}", out.join("eval.json").display());
    }
    Ok(())
}

/// The frames of `range` that have ground truth in `ds`.
///
/// # Errors
/// None of them has.
pub fn frames_with_truth(ds: &Dataset, range: FrameRange) -> Result<Vec<u32>> {
    let frames: Vec<u32> = range
        .indices()
        .into_iter()
        .filter(|&f| ds.gt_path(f).is_some())
        .collect();
    if frames.is_empty() {
        bail!(
            "no frame of {range} has ground truth in {}",
            ds.root.display()
        );
    }
    Ok(frames)
}

/// Scores every row on `frames` of `ds` at the evaluation sweep `spec`, with a progress bar;
/// with `pictures`, writes the first frame's colour-mapped answers and ground truth there.
///
/// # Errors
/// A frame that cannot be read or estimated, a picture that cannot be written.
pub fn evaluate(
    ds: &Dataset,
    frames: &[u32],
    spec: SweepSpec,
    rows: Vec<Row>,
    pictures: Option<&Path>,
) -> Result<EvalReport> {
    // The ground truth of the evaluation grid, with its sky mask for the two protocols.
    let eval = Evaluation::new(ds, frames, spec)?;
    if let Some(out) = pictures {
        let gt = &eval.truths[0].gt;
        let path = out.join(format!("{:05}_gt.png", frames[0]));
        write_index_png(&path, &gt.index, gt, spec.ndepth(), true)?;
    }
    let mut results = Vec::new();
    let bar = frames_bar()?;
    for row in rows {
        bar.reset();
        bar.set_length(frames.len() as u64);
        bar.set_prefix(row.name.clone());
        let mut scores = MethodScores::new(&row.name, *row.estimator.spec());
        let start = Instant::now();
        for (k, &f) in frames.iter().enumerate() {
            let context = || format!("{}: frame {f}", row.name);
            let images = ds.read_frame(f).with_context(context)?;
            let est = row.estimator.estimate(&images).with_context(context)?;
            let (index, m) = eval.score(k, &est).with_context(context)?;
            if k == 0
                && let Some(out) = pictures
            {
                let path = out.join(format!("{f:05}_{}.png", row.file));
                write_index_png(&path, &index, &eval.truths[k].gt, spec.ndepth(), false)?;
            }
            scores.push(f, m);
            bar.inc(1);
        }
        let seconds_per_frame = start.elapsed().as_secs_f64() / frames.len() as f64;
        results.push(scores.finish(&spec, seconds_per_frame)?);
    }
    bar.finish_and_clear();
    Ok(EvalReport::new(&eval, results))
}

/// Prints the evaluation's tables and speeds; writes `eval.json` and `eval.md` into `out`.
///
/// # Errors
/// A file that cannot be written.
pub fn report(report: &EvalReport, out: Option<&Path>) -> Result<()> {
    out!("{}", report.table());
    for m in &report.methods {
        outln!("{}: {:.3} s/frame", m.method, m.seconds_per_frame);
    }
    if let Some(out) = out {
        report.write(out)?;
        outln!("wrote {}", out.join("eval.json").display());
    }
    Ok(())
}
