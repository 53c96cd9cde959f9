//! Our metrics are the reference's: for generated frames (two of a `things` set, two of a
//! `house` set, written by `omnimvs synth`; `omnimvs sgm`'s index maps as predictions) the
//! five figures that the reference implementation's own `loadGTInvdepthIndex` + `evalError`
//! gave (hyu-cvlab/omnimvs-pytorch; `reference.json`, made by
//! `scripts/reference_parity/make_reference_fixture.py --synth ... --pred ...`) are what our
//! scoring path gives for the same files: `eval_truth_on_grid` (centre crop, the closing rule,
//! sky left out) and `protocol_metrics` under [`Protocol::Reference`], as `omnimvs eval`,
//! `sgm` and `infer` score. The script also checked that the reference's `Dataset` loads the
//! generated folders unchanged (config, masks, images, the two-page ground truth, the split).
//!
//! Tolerance 1e-3 (percentages and percent-of-N errors): the reference sums in f64 over
//! numpy's f32 differences, we in f64 too; only the last bits of a mean can differ.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::path::{Path, PathBuf};

use omnimvs_data::gt::{eval_truth_on_grid, read_inv_depth};
use omnimvs_eval::metrics::{Protocol, protocol_metrics};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use support::read_json;

const TOLERANCE: f64 = 1e-3;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference")
}

/// A prediction stored as 16-bit `round(index * scale)`.
fn prediction(path: &Path, scale: f32) -> Vec<f32> {
    let image = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_luma16();
    image
        .into_raw()
        .into_iter()
        .map(|v| f32::from(v) / scale)
        .collect()
}

#[test]
fn eval_gives_the_reference_evalerror_figures_on_generated_frames() {
    let report = read_json(&fixtures().join("reference.json"));
    let sets = report["metrics"]
        .as_array()
        .expect("reference.json: metrics");
    assert_eq!(sets.len(), 2, "a things set and a house set");
    let grid = EquirectGrid::new(160, 640, 45.0).unwrap();
    let ndepth = 192;
    let mut worst = 0f64;
    for set in sets {
        let name = set["dataset"].as_str().unwrap();
        let min_depth = set["min_depth_m"].as_f64().unwrap();
        let scale = set["pred_scale"].as_f64().unwrap() as f32;
        let hyps = InvDepthHypotheses::new(ndepth, min_depth).unwrap();
        let dir = fixtures().join("metrics").join(name);
        let frames = set["frames"].as_array().unwrap();
        assert!(frames.len() >= 2, "{name}");
        let mut sums = [0f64; 5];
        for frame in frames {
            let k = frame["frame"].as_u64().unwrap();
            let gt = read_inv_depth(&dir.join(format!("{k:05}_gt.tiff"))).unwrap();
            let truth = eval_truth_on_grid(&gt, &hyps, &grid).unwrap();
            let pred = prediction(&dir.join(format!("{k:05}_pred.png")), scale);
            let m = protocol_metrics(&pred, &truth, ndepth, Protocol::Reference).unwrap();
            let ours = [m.over1_pct, m.over3_pct, m.over5_pct, m.mae, m.rms];
            let theirs: Vec<f64> = frame["errors"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
                worst = worst.max((a - b).abs());
                assert!(
                    (a - b).abs() <= TOLERANCE,
                    "{name} frame {k}: figure {i} (>1, >3, >5, MAE, RMS) is {a}, the reference's {b}\nours {ours:?}\ntheirs {theirs:?}"
                );
                sums[i] += a;
            }
        }
        // The dataset's figures: the mean over frames, as the reference's test script reports.
        let mean: Vec<f64> = set["mean"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for (i, b) in mean.iter().enumerate() {
            let a = sums[i] / frames.len() as f64;
            assert!((a - b).abs() <= TOLERANCE, "{name} mean {i}: {a} vs {b}");
        }
    }
    eprintln!("largest difference to the reference's figures: {worst:e}");
}

/// The sets the fixture was made from stated the reference's split as `synth` writes it: a
/// `things` set of frames 1-2 is all training frames (OmniThings' test frames are
/// 4097-5120), a `house` set of frames 2048-2049 has one of each (OmniHouse's start at 2049).
#[test]
fn the_reference_read_the_split_that_synth_writes() {
    let report = read_json(&fixtures().join("reference.json"));
    let sets = report["metrics"].as_array().unwrap();
    let split = |name: &str| {
        let set = sets.iter().find(|s| s["dataset"] == name).unwrap();
        (set["train_idx"].clone(), set["test_idx"].clone())
    };
    assert_eq!(
        split("things"),
        (serde_json::json!([1, 2]), serde_json::json!([]))
    );
    assert_eq!(
        split("house"),
        (serde_json::json!([2048]), serde_json::json!([2049]))
    );
}

/// What the reference's `Dataset` needs from a generated folder's `config.yaml`, as `synth`
/// writes it now (the fixture's folders were checked by the reference itself): ground truth
/// announced (`dtype: gt`, `gt_phi`), the split (OmniThings' test frames start at 4097), and
/// every camera's `invalid_mask` file.
#[test]
fn synth_writes_what_the_reference_dataset_reads() {
    let dir = tempfile::tempdir().unwrap();
    let data = support::synth_dataset(dir.path(), "things", "4096..4097", "48x50", 3);
    let text = std::fs::read_to_string(data.join("config.yaml")).unwrap();
    let yaml: serde_json::Value = {
        // The few keys the reference reads from `dataset:`, one per line.
        let mut map = serde_json::Map::new();
        for line in text.lines().map(str::trim) {
            for key in ["dtype", "gt_phi", "train_idx", "test_idx"] {
                if let Some(v) = line.strip_prefix(&format!("{key}: ")) {
                    map.insert(key.into(), v.into());
                }
            }
        }
        map.into()
    };
    assert_eq!(yaml["dtype"], "gt", "{text}");
    assert_eq!(yaml["gt_phi"], "90.0", "{text}");
    assert_eq!(yaml["train_idx"], "[4096]", "{text}");
    assert_eq!(yaml["test_idx"], "[4097]", "{text}");
    for camera in 1..=4 {
        assert!(
            text.contains(&format!("invalid_mask: \"mask{camera}.png\"")),
            "{text}"
        );
        assert!(data.join(format!("mask{camera}.png")).is_file());
    }
    assert!(data.join("omnidepth_gt_640/04097.tiff").is_file());
}
