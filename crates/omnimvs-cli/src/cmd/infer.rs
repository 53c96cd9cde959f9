//! `omnimvs infer`: run the OmniMVS network on a dataset's frames.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_camera::fs::write_atomic;
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::gt::write_f32_tiff;
use omnimvs_data::image_io::write_png_u8;
use omnimvs_data::metrics::{Protocol, ProtocolMetrics, eval_metrics};
use omnimvs_data::ply::write_ply;
use omnimvs_data::{Dataset, FrameRange};
use omnimvs_net::Backend;
use omnimvs_net::NetEstimator;
use omnimvs_net::infer::FrameResult;
use omnimvs_net::weights::common_image_size;
use omnimvs_sweep::{CacheStatus, GrayImage, InvDepthSource, LutCache, compose_panorama};

use crate::args::{BACKEND_HELP, Preset, Size, parse_backend};
use crate::cmd::eval::protocol_tables;
use crate::pictures::{error_map, fisheye_strip, gray_to_rgb, point_cloud};
use crate::weights::{BUNDLED, Weights};

/// Estimate 360-degree inverse depth with the OmniMVS network.
///
/// Writes per frame
/// OUT/%05d.tiff (f32 inverse depth, 1/m), %05d_index.tiff (hypothesis index),
/// %05d_entropy.tiff, %05d.png (colour-mapped inverse depth), %05d_vis.png
/// (inputs, panorama, depth, entropy and error when ground truth exists) and
/// optionally %05d.ply; metrics.json when ground truth exists, scored at the
/// network's own grid under the `reference` protocol (the reference's evalError,
/// the paper's tables: sky is not scored) with the `with-sky` protocol (sky
/// scored as index 0) beside it (`omnimvs eval` compares methods at one grid).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder (or its config.yaml).
    pub dataset: PathBuf,
    /// Weights: `bundled` (the `omnimvs-tiny` model compiled into the binary, the
    /// default), our .safetensors (with its .json beside it), a reference PyTorch
    /// checkpoint (.pt/.pth with net_state_dict and CH), or `random` for a randomly
    /// initialised --preset network (smoke tests, timing).
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
    /// Also write a PLY point cloud coloured by the panorama.
    #[arg(long)]
    pub ply: bool,
    /// Camera concatenation order, e.g. 0,1,2,3 (default: the rig's order).
    #[arg(long, value_delimiter = ',')]
    pub order: Option<Vec<usize>>,
    /// Size the images are fed to the network at: `model` (the size the model's
    /// configuration names, e.g. 768x800, what our models were trained at), `native` (each
    /// camera's own image size, as the reference implementation runs its checkpoints) or
    /// HEIGHTxWIDTH. Default: `native` for a reference PyTorch checkpoint, `model` otherwise.
    /// infer.json records the size used.
    #[arg(long)]
    pub input_size: Option<InputSize>,
}

/// `--input-size` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputSize {
    /// The model configuration's size.
    Model,
    /// The cameras' own image size.
    Native,
    /// A given size.
    Fixed(Size),
}

impl std::str::FromStr for InputSize {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "model" => Ok(Self::Model),
            "native" => Ok(Self::Native),
            size => size
                .parse()
                .map(Self::Fixed)
                .map_err(|e: String| format!("expected `model`, `native` or HEIGHTxWIDTH: {e}")),
        }
    }
}

impl std::fmt::Display for InputSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Model => f.write_str("model"),
            Self::Native => f.write_str("native"),
            Self::Fixed(size) => write!(f, "{size}"),
        }
    }
}

/// The input size `--input-size` asks for with these weights (`None`: the model's own).
///
/// # Errors
/// `native` on a rig whose cameras have different image sizes.
pub fn input_size(
    asked: Option<InputSize>,
    weights: &Weights,
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
        InputSize::Native => match common_image_size(&ds.rig) {
            Ok(size) => Some(size),
            Err(sizes) => {
                let Some(first) = sizes.first() else {
                    bail!("{}: the rig has no camera", ds.config_path.display());
                };
                let other = sizes.iter().position(|s| s != first).unwrap_or_default();
                bail!(
                    "{}: --input-size native needs one image size for every camera; camera 1 \
                     is {}x{}, camera {} is {}x{} (give --input-size HEIGHTxWIDTH)",
                    ds.config_path.display(),
                    first[0],
                    first[1],
                    other + 1,
                    sizes[other][0],
                    sizes[other][1]
                );
            }
        },
    })
}

pub fn run(args: &Args) -> Result<()> {
    let device = args.backend.device()?;
    let ds = crate::dataset::open_dataset(&args.dataset)?;
    let mut net = args.weights.load_family(args.preset.name(), &device)?;
    if let Some(size) = input_size(args.input_size, &args.weights, &ds)? {
        net.set_input_size(size)
            .with_context(|| format!("--input-size {}x{}", size[0], size[1]))?;
    }
    let config = net.config().clone();
    let (mut inference, status) = NetEstimator::new(
        net,
        &ds,
        &LutCache::default_location(),
        device,
        args.backend.is_gpu(),
    )?;
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
    if let Some(order) = &args.order {
        inference.set_order(order)?;
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let settings = serde_json::json!({
        "dataset": args.dataset,
        "weights": args.weights,
        "network": config,
        "input_size": [config.input_height, config.input_width],
        "order": inference.order(),
        "backend": args.backend.to_string(),
    });
    let path = args.out.join("infer.json");
    write_atomic(
        &path,
        (serde_json::to_string_pretty(&settings)? + "\n").as_bytes(),
    )
    .with_context(|| format!("writing {}", path.display()))?;

    let frames: Vec<u32> = args.frames.indices();
    let bar = ProgressBar::new(frames.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:30} {pos}/{len} frames, {elapsed} elapsed, eta {eta} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut metrics: Vec<(u32, ProtocolMetrics)> = Vec::new();
    for &frame in &frames {
        let images = ds
            .read_frame(frame)
            .with_context(|| format!("frame {frame}"))?;
        let result = inference
            .run(&images)
            .with_context(|| format!("frame {frame}"))?;
        let error = write_frame(args, &ds, &inference, frame, &images, &result)?;
        if let Some(m) = error {
            bar.set_message(format!("frame {frame}: MAE {:.3}", m.reference.mae));
            metrics.push((frame, m));
        } else {
            bar.set_message(format!("frame {frame}: {:.2} s", result.seconds));
        }
        bar.inc(1);
    }
    bar.finish();
    if !metrics.is_empty() {
        let rows: Vec<ProtocolMetrics> = metrics.iter().map(|(_, m)| *m).collect();
        let mean = ProtocolMetrics::mean(&rows);
        let json = serde_json::json!({
            "protocol": Protocol::Reference,
            "frames": metrics.iter().map(|(f, m)| serde_json::json!({
                "frame": f,
                "metrics": m.reference,
                "metrics_with_sky": m.with_sky,
            })).collect::<Vec<_>>(),
            "mean": mean.map(|m| m.reference),
            "mean_with_sky": mean.map(|m| m.with_sky),
        });
        let path = args.out.join("metrics.json");
        write_atomic(
            &path,
            (serde_json::to_string_pretty(&json)? + "\n").as_bytes(),
        )
        .with_context(|| format!("writing {}", path.display()))?;
        if let Some(mean) = mean {
            let c = inference.config();
            out!(
                "{}x{}, N = {} (the network's grid)\n\n{}",
                c.out_height,
                c.out_width,
                c.num_invdepth,
                protocol_tables(&[("OmniMVS (burn)".into(), mean)])
            );
        }
    }
    outln!("wrote {} frames to {}", frames.len(), args.out.display());
    Ok(())
}

/// Writes every output of one frame; returns its metrics (both protocols) when ground truth
/// exists.
fn write_frame(
    args: &Args,
    ds: &Dataset,
    inference: &NetEstimator,
    frame: u32,
    images: &[GrayImage],
    result: &FrameResult,
) -> Result<Option<ProtocolMetrics>> {
    let (w, h) = (result.width, result.height);
    let out = |suffix: &str| args.out.join(format!("{frame:05}{suffix}"));
    write_f32_tiff(&out(".tiff"), w, h, &result.inv_depth)?;
    write_f32_tiff(&out("_index.tiff"), w, h, &result.index)?;
    write_f32_tiff(&out("_entropy.tiff"), w, h, &result.entropy)?;
    let max_inv = inference.hypotheses().max_inv_depth();
    let depth_rgb = colorize(&result.inv_depth, 0.0, max_inv, Colormap::Turbo, None);
    write_png_u8(&out(".png"), w, h, 3, &depth_rgb)?;

    let ndepth = inference.config().num_invdepth;
    let truth = ds.eval_truth(frame, inference.grid(), inference.hypotheses())?;
    let metrics = truth
        .as_ref()
        .map(|truth| eval_metrics(&result.index, truth, ndepth))
        .transpose()?;

    let pano = compose_panorama(
        &ds.rig,
        inference.grid(),
        images,
        Some(inference.masks()),
        InvDepthSource::Map(&result.inv_depth),
    )?;
    let entropy_rgb = colorize(
        &result.entropy,
        0.0,
        (ndepth as f64).ln(),
        Colormap::Inferno,
        None,
    );
    let mut rows: Vec<Vec<u8>> = vec![
        fisheye_strip(images, w),
        gray_to_rgb(&pano.image),
        depth_rgb,
        entropy_rgb,
    ];
    if let Some(truth) = &truth {
        rows.push(error_map(&result.index, &truth.gt, ndepth));
    }
    let composite: Vec<u8> = rows.concat();
    write_png_u8(
        &out("_vis.png"),
        w,
        composite.len() / (3 * w),
        3,
        &composite,
    )?;

    if args.ply {
        let points = point_cloud(inference.grid(), &result.inv_depth, &pano.image.data);
        write_ply(&out(".ply"), &points)?;
    }
    Ok(metrics)
}
