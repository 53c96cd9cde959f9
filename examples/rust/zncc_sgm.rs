//! ZNCC + SGM, the classical method of the OmniMVS paper's Table 3, on a dataset folder: no
//! network, no GPU.
//!
//! ```text
//! cargo run --release -p omnimvs-examples --example zncc_sgm -- DATASET OUT [FRAMES]
//! ```
//!
//! DATASET is a folder in the reference layout (`config.yaml` and the cameras' images, e.g. the
//! reference implementation's `itbt_sample`), or a released dataset's folder (`ocamN.txt` and
//! `poses.txt`); FRAMES is `A..B` or one frame (default: every frame found). OUT gets what
//! `omnimvs sgm` writes: per frame `%05d.tiff` (inverse depth, 1/m, f32), `%05d_index.tiff`
//! (hypothesis index), `%05d_invdepth.png` (colour map), `%05d_confidence.png/.tiff`; and
//! `sgm.json` (parameters, timings), with `metrics.md` when the frames have ground truth.

use std::path::Path;

use anyhow::{Context, Result};
use omnimvs_data::{Dataset, DepthEstimator, FrameRange, StageTimes};
use omnimvs_eval::output::ConfidenceRun;
use omnimvs_stereo::{SgmEstimator, SgmParams};

const USAGE: &str = "usage: zncc_sgm DATASET OUT [FRAMES]

Runs ZNCC + SGM on the frames of DATASET (a folder with config.yaml) and writes the inverse
depth maps, pictures and reports into OUT. FRAMES: A..B or a single frame (default: all).";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (dataset, out, frames) = match args.as_slice() {
        [dataset, out] => (dataset, out, None),
        [dataset, out, frames] => (dataset, out, Some(frames)),
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let out = Path::new(out);

    // Opening a dataset reads its config.yaml only: the rig (cameras, poses, validity masks),
    // the minimum depth and where the images are.
    let ds = Dataset::open(Path::new(dataset)).with_context(|| format!("opening {dataset}"))?;
    let frames = match frames {
        Some(text) => text.parse::<FrameRange>()?.indices(),
        None => ds.frames_found(),
    };
    anyhow::ensure!(!frames.is_empty(), "{dataset}: no frame found");

    // The sweep every estimate answers on: the paper's 160x640 equirectangular grid over
    // +-45 degrees of latitude, with N = 192 inverse-depth hypotheses (spheres) from the rig's
    // minimum depth to infinity.
    let spec = ds.sweep_spec(160, 640, 45.0, 192)?;
    // The method prepared once for this rig and sweep; the masks tell it which fisheye pixels
    // see the scene (not the robot). SgmParams::default() holds the tuned penalties
    // (P1 = 0.1, P2 = 2.0), 8 paths and the 5x5 median.
    let stereo = SgmEstimator::new(&ds.rig, Some(ds.masks()?), spec, SgmParams::default())?;
    println!(
        "{}: {} cameras, frames {:?}, {}x{}, N = {}",
        stereo.name(),
        ds.rig.len(),
        frames,
        spec.height(),
        spec.width(),
        spec.ndepth()
    );

    // A run writes each frame's files as it comes and the reports at the end.
    let mut run = ConfidenceRun::new(out, spec)?;
    for frame in frames {
        // The gray images of every camera, in the rig's order.
        let images = ds.read_frame(frame)?;
        // `estimate` would do; `estimate_observed` also reports each stage's time.
        let mut times = StageTimes::default();
        let est = stereo.estimate_observed(&images, &mut times)?;
        // Ground truth on the same grid, when the dataset has it (None otherwise).
        let truth = ds.eval_truth(frame, &spec)?;
        let record = run.add(frame, &est, times, truth.as_ref())?;
        let metrics = record.protocol_metrics().map_or(String::new(), |m| {
            format!(", MAE {:.2} % of N (reference protocol)", m.reference.mae)
        });
        println!(
            "frame {frame}: {:.2} s (warp {:.2}, cost {:.2}, aggregation {:.2}){metrics}",
            est.seconds,
            record.timings.get("warp"),
            record.timings.get("cost"),
            record.timings.get("aggregation"),
        );
    }
    let table = run.finish(&ds, stereo.name(), stereo.params(), "sgm.json")?;
    if let Some(table) = table {
        println!("\n{table}");
    }
    println!("wrote {}", out.display());
    Ok(())
}
