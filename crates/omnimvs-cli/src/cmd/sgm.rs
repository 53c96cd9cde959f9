//! `omnimvs sgm`: the classical method (spherical-sweep ZNCC + SGM) on the
//! frames of a dataset.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use omnimvs_camera::ValidityMask;
use omnimvs_core::{ColourPlanes, GrayImage};
use omnimvs_data::gt::EvalTruth;
use omnimvs_data::{Dataset, DepthEstimate, DepthEstimator, FrameRange, Speed, StageTimes};
use omnimvs_eval::output::{ConfidenceRun, FrameScene};
use omnimvs_net::NetError;
use omnimvs_net::learned_sgm::{MatchingCost, sgm_estimator};
use omnimvs_stereo::{Directions, SgmEstimator, SgmParams, SweepStep};
use omnimvs_sweep::SweepSpec;

use crate::args::{Cost, SweepArgs};
use crate::pipeline::RunReport;

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
/// %05d_confidence.png/.tiff (1 - best/second-best aggregated cost),
/// optionally %05d.ply (a point cloud coloured by the panorama, in colour when the images
/// are); and sgm.json (the parameters, timings and, when the dataset has ground
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
    /// Also write a PLY point cloud coloured by the panorama at the estimated depth (in
    /// colour when the frame's images are).
    #[arg(long)]
    pub ply: bool,
    /// Output grid and hypotheses.
    #[command(flatten)]
    pub sweep: SweepArgs,
    /// Speed preset, traded against accuracy: `fast` (32 spheres), `balanced` (64) or
    /// `accurate` (192, the paper's and the default); the README's speed/accuracy table scores
    /// each. Instead of --ndepth.
    #[arg(long, conflicts_with = "ndepth")]
    pub speed: Option<Speed>,
    /// Matching cost: zncc (9x9 ZNCC, the paper's ZNCC+SGM), mccnn (the MC-CNN-style
    /// learned cost, MC-CNN+SGM) or sweepnet (the SweepNet-style learned cost on the warped
    /// images, SweepNet+SGM); learned weights from --cost-weights.
    #[arg(long, value_enum, default_value_t = Cost::Zncc)]
    pub cost: Cost,
    /// Weights of a learned cost: bundled (compiled in), random, or a .safetensors file
    /// (with its .json) written by `omnimvs train --cost mccnn|sweepnet`.
    #[arg(long, default_value = "bundled")]
    pub cost_weights: String,
    /// SGM penalty for a change of one hypothesis, in matching-cost units
    /// ((1 - zncc) / 2 or (1 - cos) / 2, in [0, 1]; default: 0.1 for ZNCC, the learned
    /// cost's own tuned value otherwise).
    #[arg(long)]
    pub p1: Option<f32>,
    /// SGM penalty for larger jumps, same units (>= P1; default: 2.0 for ZNCC, the learned
    /// cost's own otherwise).
    #[arg(long)]
    pub p2: Option<f32>,
    /// Aggregate along 4 paths instead of 8.
    #[arg(long)]
    pub four_paths: bool,
    /// Match on every other sphere only (about half the time; odd
    /// hypotheses interpolated).
    #[arg(long)]
    pub every_other: bool,
    /// Side of the median filter on the index map after WTA (odd; 0 or 1: none).
    #[arg(long, default_value_t = omnimvs_stereo::DEFAULT_MEDIAN)]
    pub median: usize,
    /// Leave pixels whose confidence (1 - best / second-best aggregated cost) is below this
    /// without an answer (NaN in the outputs; the metrics are over the others and report
    /// their share as coverage). 0: every pixel answers.
    #[arg(long, default_value_t = 0.0)]
    pub min_confidence: f32,
}

impl Args {
    /// The method's parameters (`defaults`: the cost's own penalties).
    pub fn params(&self, defaults: (f32, f32)) -> SgmParams {
        SgmParams {
            p1: self.p1.unwrap_or(defaults.0),
            p2: self.p2.unwrap_or(defaults.1),
            directions: if self.four_paths {
                Directions::Four
            } else {
                Directions::Eight
            },
            sweep: if self.every_other {
                SweepStep::EveryOther
            } else {
                SweepStep::All
            },
            median: self.median,
            min_confidence: self.min_confidence,
            ..SgmParams::default()
        }
    }
}

/// The SGM estimator of a matching cost on a dataset's rig: ZNCC, or a learned cost from
/// `weights` (`bundled`, `random` or a file) on the CPU; `params` gets the cost's default
/// penalties `(P1, P2)`.
///
/// # Errors
/// Unloadable weights or a rig that does not fit.
pub fn estimator(
    ds: &Dataset,
    spec: SweepSpec,
    cost: Cost,
    weights: &str,
    params: impl Fn((f32, f32)) -> SgmParams,
) -> Result<SgmEstimator> {
    let cost = match cost {
        Cost::Zncc => MatchingCost::Zncc,
        Cost::Mccnn => MatchingCost::McCnn,
        Cost::Sweepnet => MatchingCost::SweepNet,
    };
    // Errors of the method's own parameters say which; the others come from the weights.
    sgm_estimator(&ds.rig, ds.masks()?, spec, cost, weights, params).map_err(|e| match e {
        NetError::Stereo(_) => anyhow::Error::new(e),
        e => anyhow::Error::new(e).context(format!("--cost-weights {weights}")),
    })
}

/// The line that presents the method's settings.
pub fn header(ds: &Dataset, stereo: &SgmEstimator) -> String {
    let (spec, params) = (stereo.spec(), stereo.params());
    format!(
        "{}: {} cameras, {}x{} (+-{} deg), N = {}, min depth {} m, P1 = {}, P2 = {}, {} paths, {:?} spheres",
        stereo.name(),
        ds.rig.len(),
        spec.height(),
        spec.width(),
        spec.grid.phi_deg,
        spec.ndepth(),
        ds.config.min_depth_m,
        params.p1,
        params.p2,
        params.directions.count(),
        params.sweep
    )
}

/// One frame by the classical method into `run`: the estimate, its files, its metrics when
/// the frame has ground truth, and the line that reports it.
///
/// # Errors
/// An unreadable frame, a failing estimate or a file that cannot be written.
pub fn frame(
    ds: &Dataset,
    stereo: &SgmEstimator,
    run: &mut ConfidenceRun,
    frame: u32,
    images: &[GrayImage],
) -> Result<DepthEstimate> {
    let truth = frame_truth(ds, stereo, frame);
    let (est, timings) = estimate(stereo, images)?;
    record(run, frame, &est, timings, truth.as_ref())?;
    Ok(est)
}

/// The frame's ground truth on the method's grid; `None` (said on stderr) when it has none
/// or it cannot be read.
fn frame_truth(ds: &Dataset, stereo: &SgmEstimator, frame: u32) -> Option<EvalTruth> {
    ds.eval_truth(frame, stereo.spec()).unwrap_or_else(|e| {
        eprintln!("frame {frame}: no metrics: {e}");
        None
    })
}

/// The estimate of one frame and the time of each stage.
fn estimate(stereo: &SgmEstimator, images: &[GrayImage]) -> Result<(DepthEstimate, StageTimes)> {
    let mut timings = StageTimes::default();
    let est = stereo.estimate_observed(images, &mut timings)?;
    Ok((est, timings))
}

/// Writes one frame's files into `run` and prints the line that reports it.
fn record(
    run: &mut ConfidenceRun,
    frame: u32,
    est: &DepthEstimate,
    timings: StageTimes,
    truth: Option<&EvalTruth>,
) -> Result<()> {
    let t = |name| timings.get(name);
    let line = format!(
        "frame {frame:5}: warp {:.2} s, cost {:.2} s, aggregation {:.2} s, wta {:.2} s, total {:.2} s",
        t("warp"),
        t("cost"),
        t("aggregation"),
        t("wta"),
        t("total"),
    );
    let record = run.add(frame, est, timings, truth)?;
    let metrics = record.protocol_metrics().map_or(String::new(), |m| {
        let (r, s) = (m.reference, m.with_sky);
        format!(
            "; >1 {:.2}% >3 {:.2}% >5 {:.2}% MAE {:.2} RMS {:.2} (with sky: MAE {:.2} RMS {:.2})",
            r.over1_pct, r.over3_pct, r.over5_pct, r.mae, r.rms, s.mae, s.rms
        )
    });
    outln!("{line}{metrics}");
    Ok(())
}

/// Writes the run's reports and prints its table, when frames had ground truth.
///
/// # Errors
/// A file that cannot be written.
pub fn finish(ds: &Dataset, stereo: &SgmEstimator, run: ConfidenceRun, out: &Path) -> Result<()> {
    let written = run.len();
    if let Some(table) = run.finish(ds, stereo.name(), stereo.params(), "sgm.json")? {
        out!("{table}");
    }
    outln!("wrote {written} frames to {}", out.display());
    Ok(())
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    let ds = datasets.open(&args.dataset)?;
    let frames: Vec<u32> = match &args.frames {
        Some(range) => range.indices(),
        None => ds.frames_found(),
    };
    if frames.is_empty() {
        bail!("{}: no frame found", ds.root.display());
    }
    let mut sweep = args.sweep;
    if let Some(speed) = args.speed {
        sweep.ndepth = speed.sgm_ndepth();
    }
    let spec = sweep.spec(&ds)?;
    let stereo = estimator(&ds, spec, args.cost, &args.cost_weights, |d| args.params(d))?;
    let run = ConfidenceRun::new(&args.out, spec)?;
    outln!("{}", header(&ds, &stereo));
    let clouds = if args.ply {
        Some(PointClouds {
            dir: &args.out,
            masks: ds.masks()?,
        })
    } else {
        None
    };
    crate::pipeline::stop_on_ctrl_c();
    let (run, report) = pipelined(&ds, &stereo, run, &frames, clouds.as_ref())?;
    finish(&ds, &stereo, run, &args.out)?;
    outln!("{}", report.summary());
    crate::pipeline::check_not_stopped(&report, frames.len(), &args.out.join("sgm.json"))
}

/// Where `--ply` writes its point clouds, and the cameras' masks their panoramas need.
struct PointClouds<'a> {
    dir: &'a Path,
    masks: Vec<ValidityMask>,
}

impl PointClouds<'_> {
    /// Writes frame `frame`'s point cloud: the panorama at the estimated depth (in colour
    /// with `colour`), one point per grid pixel.
    fn write(
        &self,
        ds: &Dataset,
        frame: u32,
        est: &DepthEstimate,
        images: &[GrayImage],
        colour: Option<&[ColourPlanes]>,
    ) -> Result<()> {
        let scene = FrameScene {
            rig: &ds.rig,
            images,
            masks: &self.masks,
            colour,
        };
        let pano = scene.panorama(est)?;
        scene.write_point_cloud(self.dir, frame, est, &pano)?;
        Ok(())
    }
}

/// The frames one after the other through [`crate::pipeline::run_frames`]: the same files
/// and lines as [`frame`] frame by frame, in order.
///
/// # Errors
/// As [`frame`].
fn pipelined(
    ds: &Dataset,
    stereo: &SgmEstimator,
    mut run: ConfidenceRun,
    frames: &[u32],
    clouds: Option<&PointClouds<'_>>,
) -> Result<(ConfidenceRun, RunReport)> {
    let report = crate::pipeline::run_frames(
        frames,
        |f| {
            // Colour is decoded (with the gray, in one read) only for the point clouds.
            let (images, colour) = if clouds.is_some() {
                ds.read_frame_and_colour(f)?
            } else {
                (ds.read_frame(f)?, None)
            };
            Ok((images, colour, frame_truth(ds, stereo, f)))
        },
        |_, (images, colour, truth)| Ok((estimate(stereo, &images)?, images, colour, truth)),
        |f, ((est, timings), images, colour, truth)| {
            record(&mut run, f, &est, timings, truth.as_ref())?;
            if let Some(clouds) = clouds {
                clouds
                    .write(ds, f, &est, &images, colour.as_deref())
                    .with_context(|| format!("frame {f}: point cloud"))?;
            }
            Ok(())
        },
    )?;
    Ok((run, report))
}
