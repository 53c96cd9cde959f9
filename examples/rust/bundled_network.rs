//! The bundled network on a dataset folder: the default `cascade` (160x640, N = 192, with its
//! learnt picks after it), or the small `tiny` (the paper's network at 32x128, N = 64). The
//! weights are compiled into the library, so nothing is downloaded; it runs on the CPU.
//!
//! ```text
//! cargo run --release -p omnimvs-examples --example bundled_network -- DATASET OUT [FRAMES] [MODEL]
//! ```
//!
//! DATASET is a folder in the reference layout (e.g. the reference implementation's
//! `itbt_sample`); FRAMES is `A..B` or one frame (default: every frame found); MODEL is
//! `cascade` (the default) or `tiny`. OUT gets what `omnimvs infer --ply` writes: per frame
//! `%05d.tiff` (inverse depth, 1/m, f32), `%05d_index.tiff`, `%05d_entropy.tiff` (how unsure
//! each pixel is), `%05d.png` (colour map), `%05d_vis.png` (inputs, panorama, depth,
//! entropy, and the error when there is ground truth), `%05d.ply` (point cloud); `infer.json`
//! (the settings) and `metrics.json` when the frames have ground truth.

use std::path::Path;

use anyhow::{Context, Result};
use omnimvs_data::{Dataset, DepthEstimator, FrameRange};
use omnimvs_eval::output::{DepthRun, FrameScene};
use omnimvs_net::bundled::PickChoice;
use omnimvs_net::{Backend, BundledModel, NetEstimator};
use omnimvs_sweep::LutCache;

const USAGE: &str = "usage: bundled_network DATASET OUT [FRAMES] [MODEL]

Runs a bundled network on the frames of DATASET (a folder with config.yaml) and writes the
inverse depth maps, pictures and point clouds into OUT. FRAMES: A..B or a single frame
(default: all); MODEL: cascade (the default) or tiny.";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (dataset, out, frames, model) = match args.as_slice() {
        [dataset, out] => (dataset, out, None, None),
        [dataset, out, frames] => (dataset, out, Some(frames), None),
        [dataset, out, frames, model] => (dataset, out, Some(frames), Some(model)),
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let out = Path::new(out);
    let model = match model {
        Some(name) => BundledModel::from_name(name)
            .with_context(|| format!("unknown model {name:?}: expected cascade or tiny"))?,
        None => BundledModel::DEFAULT,
    };

    let ds = Dataset::open(Path::new(dataset)).with_context(|| format!("opening {dataset}"))?;
    let frames = match frames {
        Some(text) => text.parse::<FrameRange>()?.indices(),
        None => ds.frames_found(),
    };
    anyhow::ensure!(!frames.is_empty(), "{dataset}: no frame found");

    // The network's weights on a compute device. The default build has the CPU backend
    // (burn flex); builds with the `libtorch` or `wgpu` features offer GPUs (`Backend`).
    let device = Backend::Cpu.device()?;
    let net = model.load(&device)?;
    // Prepared once for this rig: the cascade projects its samples through the cameras
    // itself; the paper's network (`tiny`) reads a lookup table, built once and cached in
    // ~/.cache/omnimvs/lut (the second element, how it was found, is None for the cascade).
    let (estimator, _lut_status) =
        NetEstimator::new(net, &ds, &LutCache::default_location(), device, false)?;
    // The learnt picks that refine the cascade's answer at depth edges, as `omnimvs infer`
    // runs them by default (`Auto`: the bundled model's own picks; none after `tiny`).
    let estimator = match PickChoice::Auto.load(Some(model))? {
        Some(pick) => estimator.with_pick(pick)?,
        None => estimator,
    };
    let spec = *estimator.spec();
    println!(
        "{} ({}): {}x{}, N = {}, pick {}",
        model.name(),
        model.label(),
        spec.height(),
        spec.width(),
        spec.ndepth(),
        if estimator.has_pick() { "on" } else { "off" }
    );

    // `infer.json` records the settings; `true`: also write point clouds.
    let settings = serde_json::json!({
        "dataset": ds.root,
        "weights": model.name(),
        "pick": estimator.has_pick(),
    });
    let mut run = DepthRun::new(out, "infer.json", &settings, true)?;
    for frame in frames {
        // Gray for the network, and the colour of colour images for the point cloud.
        let (images, colour) = ds.read_frame_and_colour(frame)?;
        // Every method answers through the same trait, `DepthEstimator`, with a
        // `DepthEstimate` on its own grid: inverse depth, index, entropy, spread.
        let est = estimator.estimate(&images)?;
        // What the pictures show besides the estimate: the rig, the images, the masks.
        let scene = FrameScene {
            rig: &ds.rig,
            images: &images,
            masks: estimator.masks(),
            colour: colour.as_deref(),
        };
        let truth = ds.eval_truth(frame, &est.spec)?;
        let metrics = run.add(frame, &est, scene, truth.as_ref())?;
        let median_depth = median_depth_m(&est.inv_depth);
        let metrics = metrics.map_or(String::new(), |m| {
            format!(", MAE {:.2} % of N (reference protocol)", m.reference.mae)
        });
        println!(
            "frame {frame}: {:.2} s, median depth {median_depth:.2} m{metrics}",
            est.seconds
        );
    }
    if let Some(mean) = run.finish()? {
        println!(
            "mean over the frames with ground truth: MAE {:.2}, >1 {:.1} %, >3 {:.1} %",
            mean.reference.mae, mean.reference.over1_pct, mean.reference.over3_pct
        );
    }
    println!("wrote {}", out.display());
    Ok(())
}

/// The median depth (m) of the pixels with a finite, positive inverse depth.
fn median_depth_m(inv_depth: &[f32]) -> f32 {
    let mut depths: Vec<f32> = inv_depth
        .iter()
        .filter(|d| d.is_finite() && **d > 0.0)
        .map(|d| 1.0 / d)
        .collect();
    if depths.is_empty() {
        return f32::NAN;
    }
    depths.sort_by(f32::total_cmp);
    depths[depths.len() / 2]
}
