#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The learned matching costs end to end on small generated datasets:
//! `omnimvs sgm --cost mccnn|sweepnet` with the bundled weights writes its estimate and beats
//! the best constant answer; the bundled MC-CNN cost on a frame ranks the true sphere above a
//! wrong one far more often than chance; `omnimvs train --cost mccnn|sweepnet` trains a few
//! steps, writes its weights, and continues with `--resume`; `--min-confidence` leaves pixels
//! without an answer and reports the coverage.

mod support;

use std::path::{Path, PathBuf};

use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_data::gt::read_inv_depth;
use omnimvs_eval::metrics::eval_metrics;
use omnimvs_net::mccnn::{self, McCnnExtractor};
use omnimvs_stereo::{CameraView, SweepStep, feature_cost_volume};
use omnimvs_sweep::SphereProjector;
use support::{constant_guess_mae, read_json, run_ok, synth_dataset};

/// `omnimvs sgm DATA --frames FRAME --size SIZE --ndepth N ARGS.. --out OUT`: its standard
/// output and the index map of the frame.
fn sgm_index(
    data: &Path,
    cache: &Path,
    out: &Path,
    (frame, size, ndepth): (&str, &str, &str),
    args: &[&str],
) -> (String, Vec<f32>) {
    let mut all = vec![
        "sgm",
        data.to_str().unwrap(),
        "--frames",
        frame,
        "--size",
        size,
        "--ndepth",
        ndepth,
        "--out",
        out.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    let stdout = run_ok(&all, cache);
    let name = format!("{:05}_index.tiff", frame.parse::<u32>().unwrap());
    (stdout, read_inv_depth(&out.join(name)).unwrap().data)
}

/// Frame 1 of `data` by SGM on `cost` (80x320, N = 64) beats the best constant answer by a
/// wide margin, and reports itself as `name`.
fn sgm_finds_the_depth(data: &Path, cache: &Path, out: &Path, cost: &str, name: &str) {
    let (stdout, index) = sgm_index(data, cache, out, ("1", "80x320", "64"), &["--cost", cost]);
    assert!(stdout.contains(name), "{stdout}");
    let report = read_json(&out.join("sgm.json"));
    assert_eq!(report["ndepth"].as_u64(), Some(64), "{report}");
    let ds = Dataset::open(data).unwrap();
    let spec = ds.sweep_spec(80, 320, 45.0, 64).unwrap();
    let truth = ds.eval_truth(1, &spec).unwrap().unwrap();
    let m = eval_metrics(&index, &truth, 64).unwrap().reference;
    let constant = constant_guess_mae(&truth, 64);
    assert!(
        m.mae < 0.6 * constant,
        "{name} MAE {} against the best constant's {constant}",
        m.mae
    );
}

#[test]
fn sgm_with_the_learned_cost_finds_the_depth() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1", "384x400", 21);
    sgm_finds_the_depth(
        &data,
        &cache,
        &dir.path().join("mccnn"),
        "mccnn",
        "MC-CNN+SGM",
    );
}

#[test]
fn the_learned_cost_ranks_the_true_sphere_better_than_chance() {
    let dir = tempfile::tempdir().unwrap();
    let data = synth_dataset(dir.path(), "things", "1", "384x400", 22);
    let ds = Dataset::open(&data).unwrap();
    let spec = ds.sweep_spec(80, 320, 45.0, 64).unwrap();
    let truth = ds.eval_truth(1, &spec).unwrap().unwrap();
    let images = ds.read_frame(1).unwrap();
    let masks = ds.masks().unwrap();
    let device = Device::flex();
    let extractor = McCnnExtractor {
        net: mccnn::bundled(&device).unwrap(),
        masks: Some(masks.clone()),
        device,
    };
    let maps = extractor.feature_maps(&images).unwrap();
    let projectors: Vec<_> = ds
        .rig
        .cameras
        .iter()
        .enumerate()
        .map(|(i, c)| SphereProjector::new(c, i + 1, &spec.grid).unwrap())
        .collect();
    let views: Vec<_> = images
        .iter()
        .zip(&masks)
        .enumerate()
        .map(|(i, (img, m))| CameraView::new(img, Some(m), i + 1).unwrap())
        .collect();
    let (volume, _) = feature_cost_volume(
        &spec.grid,
        &projectors,
        &views,
        &maps,
        &spec.hypotheses,
        SweepStep::All,
    )
    .unwrap();
    // Against the sphere 16 hypotheses away (either side), at textured, non-sky pixels.
    let (mut better, mut total) = (0usize, 0usize);
    for row in 0..spec.height() {
        for col in 0..spec.width() {
            let i = row * spec.width() + col;
            let n = truth.gt.index[i];
            if !truth.gt.valid[i] || n < 1.0 {
                continue;
            }
            let n = (n.round() as usize).min(63);
            let wrong = if n >= 32 { n - 16 } else { n + 16 };
            let px = volume.pixel(row, col);
            total += 1;
            better += usize::from(px[n] < px[wrong]);
        }
    }
    let rate = better as f64 / total as f64;
    assert!(total > 1000, "{total} scored pixels");
    assert!(rate > 0.7, "true sphere cheaper at {rate:.3} of the pixels");
}

/// `omnimvs train --cost COST` on a small dataset: 2 of 4 steps, then `--resume` to 4; a
/// second run into the same folder is refused; the trained weights drive `sgm
/// --cost-weights FILE`. Returns the run folder (inside `dir`).
fn trains_resumes_and_drives_sgm(dir: &Path, cost: &str, seed: u64) -> PathBuf {
    let cache = dir.join("cache");
    let data = synth_dataset(dir, "things", "1..3", "384x400", seed);
    let run = dir.join("run");
    let first = [
        "train",
        "--cost",
        cost,
        "--data",
        data.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
        "--steps",
        "4",
        "--batch",
        "16",
        "--train-frames",
        "1..2",
        "--val-frames",
        "3..3",
        "--stop-after",
        "2",
    ];
    let stdout = run_ok(&first, &cache);
    assert!(stdout.contains("step     2"), "{stdout}");
    let stdout = run_ok(
        &["train", "--resume", run.to_str().unwrap(), "--steps", "4"],
        &cache,
    );
    assert!(stdout.contains("from step 2"), "{stdout}");
    assert!(stdout.contains("step     4"), "{stdout}");
    let lines = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 2, "{lines}");
    let again = support::omnimvs(&first, &cache);
    let err = support::text(&again.stderr);
    assert!(
        !again.status.success() && err.contains("holds a run already"),
        "{err}"
    );
    let weights = run.join("model.safetensors");
    let (stdout, _) = sgm_index(
        &data,
        &cache,
        &dir.join("sgm"),
        ("3", "40x160", "32"),
        &["--cost", cost, "--cost-weights", weights.to_str().unwrap()],
    );
    assert!(stdout.contains("wrote 1 frames"), "{stdout}");
    run
}

#[test]
fn train_cost_writes_weights_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let run = trains_resumes_and_drives_sgm(dir.path(), "mccnn", 23);
    let net = mccnn::load(&run.join("model.safetensors"), &Device::flex()).unwrap();
    assert_eq!(net.config.family, "mccnn");
}

#[test]
fn train_sweepnet_writes_weights_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let run = trains_resumes_and_drives_sgm(dir.path(), "sweepnet", 25);
    let net = omnimvs_net::sweepnet::load(&run.join("model.safetensors"), &Device::flex()).unwrap();
    assert_eq!(net.config.family, "sweepnet");
}

#[test]
fn sgm_with_the_sweepnet_cost_finds_the_depth() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1", "384x400", 24);
    let out = dir.path().join("sweepnet");
    sgm_finds_the_depth(&data, &cache, &out, "sweepnet", "SweepNet+SGM");
    // Leaving the least confident pixels without an answer: they are NaN, the metrics say
    // how many kept one.
    let (stdout, index) = sgm_index(
        &data,
        &cache,
        &dir.path().join("sparse"),
        ("1", "80x320", "64"),
        &["--min-confidence", "0.05"],
    );
    assert!(stdout.contains("coverage"), "{stdout}");
    let nan = index.iter().filter(|v| v.is_nan()).count();
    assert!(
        nan > 0 && nan < index.len(),
        "{nan} pixels without an answer"
    );
    let report = read_json(&dir.path().join("sparse").join("sgm.json"));
    let coverage = report["mean_metrics"]["coverage_pct"].as_f64();
    assert!(coverage.is_some_and(|c| c > 1.0 && c < 100.0), "{report}");
}
