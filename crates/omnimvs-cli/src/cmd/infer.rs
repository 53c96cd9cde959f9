//! `omnimvs infer`: run the OmniMVS network on a dataset's frames.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_core::{ColourPlanes, GrayImage};
use omnimvs_data::{
    Dataset, DepthEstimate, DepthEstimator, Finishing, FinishingError, FrameRange, Speed,
};
use omnimvs_eval::metrics::ProtocolMetrics;
use omnimvs_eval::output::{DepthRun, FrameScene, protocol_tables};
use omnimvs_net::bundled::PickChoice;
use omnimvs_net::weights::common_image_size;
use omnimvs_net::{Backend, NetEstimator};
use omnimvs_sweep::{CacheStatus, LutCache};

use crate::args::{BACKEND_HELP, Preset, Size, parse_backend};
use crate::weights::{BUNDLED, Weights, apply_pick, parse_pick};

/// Estimate 360-degree inverse depth with the OmniMVS network.
///
/// Writes per frame
/// OUT/%05d.tiff (f32 inverse depth, 1/m), %05d_index.tiff (hypothesis index),
/// %05d_entropy.tiff, %05d_spread.tiff (the cascade's), %05d.png (colour-mapped inverse
/// depth), %05d_vis.png
/// (inputs, panorama, depth, entropy and error when ground truth exists) and
/// optionally %05d.ply (coloured by the panorama, in colour when the images are);
/// metrics.json when ground truth exists, scored at the
/// network's own grid under the `reference` protocol (the reference's evalError,
/// the paper's tables: sky is not scored) with the `with-sky` protocol (sky
/// scored as index 0) beside it (`omnimvs eval` compares methods at one grid).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder (or its config.yaml).
    pub dataset: PathBuf,
    /// Weights: `bundled` (the default: the cascade model compiled into the binary,
    /// answering at 160x640 with N = 192), a bundled model by name (`cascade`, or `tiny`:
    /// the paper's network, small, at 32x128 with N = 64), our .safetensors (with its .json
    /// beside it), a reference PyTorch checkpoint (.pt/.pth with net_state_dict and CH), or
    /// `random` for a randomly initialised --preset network (smoke tests, timing).
    #[arg(long, default_value = BUNDLED, value_parser = Weights::parse)]
    pub weights: Weights,
    /// Architecture sizes for a PyTorch checkpoint or `--weights random`: paper, tiny or
    /// cascade.
    #[arg(long, value_enum, default_value_t = Preset::Paper)]
    pub preset: Preset,
    /// Frames, A..B (inclusive) or a single frame.
    #[arg(long)]
    pub frames: FrameRange,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long, default_value = "cpu", value_parser = parse_backend, help = BACKEND_HELP)]
    pub backend: Backend,
    /// Also write a PLY point cloud coloured by the panorama at the estimated depth (in
    /// colour when the frame's images are).
    #[arg(long)]
    pub ply: bool,
    /// Camera concatenation order, e.g. 0,1,2,3 (default: the rig's order).
    #[arg(long, value_delimiter = ',')]
    pub order: Option<Vec<usize>>,
    /// Size the images are fed to the network at: `model` (the size the model's
    /// configuration names, e.g. 768x800, what our models were trained at), `native` (each
    /// camera's own image size, as the reference implementation runs its checkpoints),
    /// `angular` (the size at which the cameras show the angular resolution, in pixels per
    /// radian, that the published rig shows at the model's size: for lenses and image sizes
    /// unlike the published rig's; `omnimvs info` prints each camera's) or HEIGHTxWIDTH. Default: `native` for a reference PyTorch checkpoint, `model` otherwise.
    /// infer.json records the size used.
    #[arg(long)]
    pub input_size: Option<InputSize>,
    /// Speed preset, traded against accuracy: `fast` (half the model's input size, no learnt
    /// pick), `balanced` (no learnt pick) or `accurate` (the defaults); the README's
    /// speed/accuracy table scores each. Instead of --input-size and --pick.
    #[arg(long, conflicts_with_all = ["input_size", "pick"])]
    pub speed: Option<Speed>,
    /// Depth edges without blends: where a pixel's 3x3 neighbourhood spans more than PCT
    /// percent of the hypotheses (default 8 when the flag is given alone), the pixel takes
    /// the neighbourhood's nearer extreme, so that no point floats between two surfaces
    /// (phantom obstacles in a point cloud). On things validation frames it lowers >1, >3
    /// and >5, keeps the MAE and raises the RMS (a wrong side costs the whole step); off by
    /// default. infer.json records it.
    #[arg(long, value_name = "PCT", num_args = 0..=1, default_missing_value = "8",
          value_parser = parse_snap_pct)]
    pub snap_edges: Option<f64>,
    /// The learnt pick after the cascade: where a depth edge lies, it chooses among the answer
    /// and the nearest and farthest answers around each pixel, reading the cameras' colours
    /// there (`omnimvs_net::pick`). `auto` (the default): the bundled cascade's own picks after
    /// the bundled cascade, none after other weights: its two picks in turn, as `chain`;
    /// `off`; `single`: the bundled first pick alone (about 0.1 s a frame faster, less
    /// accurate); `chain`: the bundled pick and then a second pick
    /// trained on its answers; or a pick's .safetensors trained on the answers of the
    /// --weights network (several, comma-separated: each runs on the answer of the one
    /// before). infer.json records whether one ran.
    #[arg(long, value_name = "auto|off|single|chain|FILE[,FILE]", default_value = "auto", value_parser = parse_pick)]
    pub pick: PickChoice,
    /// Leave the pixels whose uncertainty (the entropy written to %05d_entropy.tiff, nats) is
    /// above this without an answer: NaN in the maps, left out of the point cloud; the
    /// metrics score the others and report their share as coverage (as `sgm
    /// --min-confidence`). For the bundled cascade (its coarse stage's entropy, at most ln 32
    /// = 3.47) 2.6 leaves about a tenth of a things frame's pixels. Applied after
    /// --snap-edges; infer.json records it.
    #[arg(long, value_name = "NATS", value_parser = parse_max_entropy)]
    pub max_entropy: Option<f32>,
    /// The same by the spread (%05d_spread.tiff: the standard deviation of the network's
    /// distribution across the whole range, in index units of N; the bundled cascade's is its
    /// coarse stage's), a sharper filter than the entropy: leaving out the same share of
    /// pixels, the rest has the lower error. 30 leaves about a tenth of a things frame's
    /// pixels. Applied after --max-entropy; infer.json records it.
    #[arg(long, value_name = "UNITS", value_parser = parse_max_spread)]
    pub max_spread: Option<f32>,
}

/// A number checked by one of [`Finishing`]'s rules, else what it expects (`expected`).
fn parse_finishing<T: std::str::FromStr>(
    text: &str,
    check: fn(T) -> Result<T, FinishingError>,
    expected: &str,
) -> Result<T, String> {
    let value = text
        .parse::<T>()
        .map_err(|_| format!("{text:?}: expected {expected}"))?;
    check(value).map_err(|e| e.to_string())
}

/// `--max-entropy NATS`.
fn parse_max_entropy(text: &str) -> Result<f32, String> {
    parse_finishing(
        text,
        Finishing::max_entropy,
        Finishing::MAX_ENTROPY_EXPECTED,
    )
}

/// `--max-spread UNITS`.
fn parse_max_spread(text: &str) -> Result<f32, String> {
    parse_finishing(text, Finishing::max_spread, Finishing::MAX_SPREAD_EXPECTED)
}

/// `--snap-edges PCT`.
fn parse_snap_pct(text: &str) -> Result<f64, String> {
    parse_finishing(
        text,
        Finishing::snap_edges_pct,
        Finishing::SNAP_EDGES_EXPECTED,
    )
}

/// `--input-size` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputSize {
    /// The model configuration's size.
    Model,
    /// The cameras' own image size.
    Native,
    /// The size at which the cameras show the angular resolution the model was trained at.
    Angular,
    /// A given size.
    Fixed(Size),
}

impl std::str::FromStr for InputSize {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "model" => Ok(Self::Model),
            "native" => Ok(Self::Native),
            "angular" => Ok(Self::Angular),
            size => size.parse().map(Self::Fixed).map_err(|e: String| {
                format!("expected `model`, `native`, `angular` or HEIGHTxWIDTH: {e}")
            }),
        }
    }
}

impl std::fmt::Display for InputSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Model => f.write_str("model"),
            Self::Native => f.write_str("native"),
            Self::Angular => f.write_str("angular"),
            Self::Fixed(size) => write!(f, "{size}"),
        }
    }
}

/// `--input-size` as a `--speed` preset chooses it for a model trained at `model_size`
/// (`asked` without a preset).
pub fn speed_input_size(
    speed: Option<Speed>,
    asked: Option<InputSize>,
    model_size: [usize; 2],
) -> Option<InputSize> {
    match speed {
        Some(speed) => {
            let [height, width] = speed.net_input_size(model_size);
            Some(InputSize::Fixed(Size { height, width }))
        }
        None => asked,
    }
}

/// `--pick` as a `--speed` preset chooses it (`asked` without a preset, or with `accurate`).
pub fn speed_pick(speed: Option<Speed>, asked: &PickChoice) -> PickChoice {
    match speed {
        Some(speed) if !speed.net_picks() => PickChoice::Off,
        _ => asked.clone(),
    }
}

/// The cameras' mean angular resolution (pixels per radian out to
/// [`omnimvs_camera::RESOLUTION_ANGLE_DEG`] from the axis); `None` when a camera does not see
/// that far.
fn mean_resolution<'a>(
    cameras: impl Iterator<Item = &'a omnimvs_camera::CameraModel>,
) -> Option<f64> {
    let mut n = 0.0;
    let mut sum = 0.0;
    for model in cameras {
        sum += model.angular_resolution()?;
        n += 1.0;
    }
    (n > 0.0).then(|| sum / n)
}

/// The input size at which the cameras of `rig` show the angular resolution that the
/// published rig's cameras (what the bundled models were trained on) show at the model's input
/// size `model_size`: the cameras' common image size times the ratio of the two resolutions.
///
/// # Errors
/// Cameras of different image sizes, or a camera that sees less than
/// [`omnimvs_camera::RESOLUTION_ANGLE_DEG`] from its axis.
pub fn angular_input_size(
    rig: &omnimvs_camera::Rig,
    model_size: [usize; 2],
    source: &Path,
) -> Result<[usize; 2]> {
    let published = omnimvs_synth::rig::preset_rig()?.rig;
    let [rows, cols] = model_size.map(|v| u32::try_from(v).unwrap_or(u32::MAX));
    let resized: Vec<_> = published
        .cameras
        .iter()
        .map(|c| c.model.resized(rows, cols))
        .collect();
    let Some(reference) = mean_resolution(resized.iter()) else {
        bail!("the published rig has no angular resolution at {rows}x{cols}");
    };
    let Some(ours) = mean_resolution(rig.cameras.iter().map(|c| &c.model)) else {
        bail!(
            "{}: --input-size angular needs cameras that see {} degrees from their axis",
            source.display(),
            omnimvs_camera::RESOLUTION_ANGLE_DEG
        );
    };
    let [h, w] = common_size(rig, source, "angular")?;
    let scale = reference / ours;
    Ok([h, w].map(|v| ((v as f64 * scale).round() as usize).max(2)))
}

/// The image size every camera of `rig` shares, for `--input-size NAME`.
fn common_size(rig: &omnimvs_camera::Rig, source: &Path, name: &str) -> Result<[usize; 2]> {
    match common_image_size(rig) {
        Ok(size) => Ok(size),
        Err(sizes) => {
            let Some(first) = sizes.first() else {
                bail!("{}: the rig has no camera", source.display());
            };
            let other = sizes.iter().position(|s| s != first).unwrap_or_default();
            bail!(
                "{}: --input-size {name} needs one image size for every camera; camera 1 \
                 is {}x{}, camera {} is {}x{} (give --input-size HEIGHTxWIDTH)",
                source.display(),
                first[0],
                first[1],
                other + 1,
                sizes[other][0],
                sizes[other][1]
            );
        }
    }
}

/// The input size `--input-size` asks for with these weights, whose model takes
/// `model_size` (`None`: the model's own).
///
/// # Errors
/// `native` or `angular` on a rig whose cameras have different image sizes.
pub fn input_size(
    asked: Option<InputSize>,
    weights: &Weights,
    model_size: [usize; 2],
    ds: &Dataset,
) -> Result<Option<[usize; 2]>> {
    let is_pytorch = matches!(weights, Weights::File(p)
        if p.extension().is_some_and(|e| e == "pt" || e == "pth"));
    let asked = asked.unwrap_or(if is_pytorch {
        InputSize::Native
    } else {
        InputSize::Model
    });
    Ok(match asked {
        InputSize::Model => None,
        InputSize::Fixed(size) => Some([size.height, size.width]),
        InputSize::Native => Some(common_size(&ds.rig, &ds.config_path, "native")?),
        InputSize::Angular => Some(angular_input_size(&ds.rig, model_size, &ds.config_path)?),
    })
}

/// Says where the paper's network's lookup table came from (on standard error).
pub fn report_cache(status: Option<CacheStatus>) {
    match status {
        Some(CacheStatus::Hit(p)) => eprintln!("lookup table from cache {}", p.display()),
        Some(CacheStatus::Built(p)) => {
            eprintln!("lookup table built and cached in {}", p.display())
        }
        Some(CacheStatus::BuiltNotSaved(why)) => {
            eprintln!("lookup table built (not cached: {why})")
        }
        None => {}
    }
}

/// The settings of a run, written to `infer.json`.
pub fn settings(
    dataset: &Path,
    weights: &Weights,
    net: &NetEstimator,
    backend: &Backend,
) -> serde_json::Value {
    let config = net.config();
    serde_json::json!({
        "dataset": dataset,
        "weights": weights,
        "network": config,
        "input_size": [config.input_height, config.input_width],
        "order": net.order(),
        "backend": backend.to_string(),
    })
}

/// One frame's estimate into `run` (its files, its metrics when the frame has ground truth);
/// `colour`: the frame's colour images, when they are (the point cloud's colours).
///
/// # Errors
/// Unreadable ground truth or a file that cannot be written.
pub fn frame(
    ds: &Dataset,
    net: &NetEstimator,
    run: &mut DepthRun,
    frame: u32,
    images: &[GrayImage],
    colour: Option<&[ColourPlanes]>,
    est: &DepthEstimate,
) -> Result<Option<ProtocolMetrics>> {
    let truth = ds.eval_truth(frame, &est.spec)?;
    let scene = FrameScene {
        rig: &ds.rig,
        images,
        masks: net.masks(),
        colour,
    };
    Ok(run.add(frame, est, scene, truth.as_ref())?)
}

/// Writes the run's metrics and prints their table, when frames had ground truth.
///
/// # Errors
/// A file that cannot be written.
pub fn finish(net: &NetEstimator, run: DepthRun) -> Result<()> {
    if let Some(mean) = run.finish()? {
        let spec = net.spec();
        out!(
            "{}x{}, N = {} (the network's grid)\n\n{}",
            spec.height(),
            spec.width(),
            spec.ndepth(),
            protocol_tables(&[("OmniMVS (burn)".into(), mean)])
        );
    }
    Ok(())
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    let device = args.backend.device()?;
    let ds = datasets.open(&args.dataset)?;
    let mut net = args.weights.load_family(args.preset.name(), &device)?;
    let model_size = [net.config().input_height, net.config().input_width];
    let asked_size = speed_input_size(args.speed, args.input_size, model_size);
    if let Some(size) = input_size(asked_size, &args.weights, model_size, &ds)? {
        net.set_input_size(size)
            .with_context(|| format!("--input-size {}x{}", size[0], size[1]))?;
    }
    let pick = speed_pick(args.speed, &args.pick);
    let (inference, status) = NetEstimator::new(
        net,
        &ds,
        &LutCache::default_location(),
        device,
        args.backend.is_gpu(),
    )?;
    report_cache(status);
    let mut inference = apply_pick(&pick, &args.weights, inference)?;
    if let Some(order) = &args.order {
        inference.set_order(order)?;
    }
    let finishing = Finishing {
        snap_edges_pct: args.snap_edges,
        max_entropy: args.max_entropy,
        max_spread: args.max_spread,
    };
    let mut settings = settings(&args.dataset, &args.weights, &inference, &args.backend);
    settings["rig_frame"] = serde_json::json!(ds.frame);
    settings["snap_edges_pct"] = serde_json::json!(finishing.snap_edges_pct);
    settings["max_entropy"] = serde_json::json!(finishing.max_entropy);
    settings["max_spread"] = serde_json::json!(finishing.max_spread);
    settings["pick"] = serde_json::json!(inference.has_pick());
    settings["speed"] = serde_json::json!(args.speed.map(Speed::name));
    let mut run = DepthRun::new(&args.out, "infer.json", &settings, args.ply)?;

    let frames: Vec<u32> = args.frames.indices();
    let bar = ProgressBar::new(frames.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:30} {pos}/{len} frames, {elapsed} elapsed, eta {eta} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    // Frames read one ahead and written one behind on threads of their own (see
    // `crate::pipeline`): decoding and encoding overlap the network's work.
    // Colour is decoded (with the gray, in one read) only for the point clouds.
    crate::pipeline::stop_on_ctrl_c();
    let report = crate::pipeline::run_frames(
        &frames,
        |f| {
            if args.ply {
                ds.read_frame_and_colour(f)
            } else {
                ds.read_frame(f).map(|images| (images, None))
            }
            .with_context(|| format!("frame {f}"))
        },
        |f, (images, colour)| {
            let mut est = inference
                .estimate(&images)
                .with_context(|| format!("frame {f}"))?;
            finishing.apply(&mut est);
            Ok((images, colour, est))
        },
        |f, (images, colour, est)| {
            let colour = colour.as_deref();
            match frame(&ds, &inference, &mut run, f, &images, colour, &est)? {
                Some(m) => bar.set_message(format!("frame {f}: MAE {:.3}", m.reference.mae)),
                None => bar.set_message(format!("frame {f}: {:.2} s", est.seconds)),
            }
            bar.inc(1);
            Ok(())
        },
    )?;
    bar.finish();
    finish(&inference, run)?;
    outln!("wrote {} frames to {}", report.frames, args.out.display());
    outln!("{}", report.summary());
    crate::pipeline::check_not_stopped(&report, frames.len(), &args.out.join("infer.json"))
}
