//! Scores an estimate against ground truth with the paper's metrics, under the reference
//! implementation's protocol: the estimate's `%05d.tiff` files (inverse depth, 1/m, on any
//! equirectangular grid over +-45 degrees: what `zncc_sgm`, `bundled_network`, `omnimvs sgm`
//! and `omnimvs infer` write) against the dataset's ground truth.
//!
//! ```text
//! cargo run --release -p omnimvs-examples --example evaluate -- DATASET ESTIMATE_DIR [FRAMES]
//! ```
//!
//! DATASET must have ground truth (e.g. one made by `omnimvs synth`, or by the
//! `train_own_rig` example); FRAMES is `A..B` or one frame (default: every frame of DATASET
//! with ground truth). Per pixel the error is `E = |n_hat - n*| / N * 100`, `n` the index of
//! the inverse depth among N = 192 hypotheses on the paper's 160x640 grid; a frame's figures
//! are the shares of pixels with E > 1, 3 and 5 %, the mean (MAE) and the RMS of E; the
//! dataset's are the mean over its frames. The reference protocol does not score sky.

use std::path::Path;

use anyhow::{Context, Result};
use omnimvs_data::gt::read_inv_depth;
use omnimvs_data::{Dataset, FrameRange};
use omnimvs_eval::metrics::{
    Metrics, Protocol, index_on_eval_grid, mean_metrics, protocol_metrics,
};
use omnimvs_eval::output::frame_path;
use omnimvs_sweep::EquirectGrid;

const USAGE: &str = "usage: evaluate DATASET ESTIMATE_DIR [FRAMES]

Scores the inverse-depth maps ESTIMATE_DIR/%05d.tiff against the ground truth of DATASET with
the paper's metrics (reference protocol). FRAMES: A..B or a single frame (default: every frame
with ground truth).";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (dataset, estimates, frames) = match args.as_slice() {
        [dataset, estimates] => (dataset, estimates, None),
        [dataset, estimates, frames] => (dataset, estimates, Some(frames)),
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let estimates = Path::new(estimates);
    let ds = Dataset::open(Path::new(dataset)).with_context(|| format!("opening {dataset}"))?;
    let frames: Vec<u32> = match frames {
        Some(text) => text.parse::<FrameRange>()?.indices(),
        None => ds
            .frames_found()
            .into_iter()
            .filter(|&f| ds.gt_path(f).is_some())
            .collect(),
    };
    anyhow::ensure!(!frames.is_empty(), "{dataset}: no frame with ground truth");

    // The evaluation sweep: the grid every estimate is scored on and the N whose indices the
    // error is measured in (the paper's tables: 160x640, +-45 degrees, N = 192).
    let eval = ds.sweep_spec(160, 640, 45.0, 192)?;

    let mut per_frame: Vec<Metrics> = Vec::new();
    println!("frame    >1 %    >3 %    >5 %     MAE     RMS   pixels");
    for &frame in &frames {
        // The estimate: an f32 TIFF of inverse depth (1/m). Its grid follows from its shape:
        // square pixels, so a HxW map covers +-180 H / W degrees (160x640: +-45).
        let path = frame_path(estimates, frame, ".tiff");
        let map = read_inv_depth(&path).with_context(|| format!("frame {frame}"))?;
        let grid = EquirectGrid::new(map.height, map.width, map.phi_deg())?;
        // Inverse depth -> hypothesis index of the evaluation's N, then carried to the
        // evaluation grid on the sphere (bilinear, wrapping in longitude) when the estimate
        // is on another grid (the `tiny` network answers at 32x128). NaN (no answer) stays
        // NaN and is not scored.
        let index: Vec<f32> = map
            .data
            .iter()
            .map(|&d| eval.hypotheses.index(f64::from(d)) as f32)
            .collect();
        let index = index_on_eval_grid(
            &index,
            &grid,
            &eval.hypotheses,
            &eval.grid,
            &eval.hypotheses,
        )?;
        // The ground truth on the evaluation grid (the middle 160 rows of the 320x640
        // panorama), as indices, with the reference's invalid-pixel rule and its sky mask.
        let truth = ds
            .eval_truth(frame, &eval)?
            .with_context(|| format!("frame {frame} has no ground truth"))?;
        // `Protocol::Reference`: the reference's evalError, the paper's tables (sky not
        // scored). `Protocol::WithSky` would score sky as index 0, as training does.
        let m = protocol_metrics(&index, &truth, eval.ndepth(), Protocol::Reference)?;
        println!("{}", row(&frame.to_string(), &m));
        per_frame.push(m);
    }
    // Each frame weighs the same, as in the paper.
    if let Some(mean) = mean_metrics(&per_frame) {
        println!("{}", row("mean", &mean));
    }
    Ok(())
}

/// One line of the table.
fn row(label: &str, m: &Metrics) -> String {
    format!(
        "{label:>5} {:7.2} {:7.2} {:7.2} {:7.2} {:7.2} {:8}",
        m.over1_pct, m.over3_pct, m.over5_pct, m.mae, m.rms, m.valid_pixels
    )
}
