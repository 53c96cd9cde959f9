#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The learned matching cost (issue 15) end to end on a small generated dataset:
//! `omnimvs sgm --cost mccnn` with the bundled weights writes its estimate and beats the best
//! constant answer; the bundled network's cost on a frame ranks the true sphere above a wrong
//! one far more often than chance; `omnimvs train --cost mccnn` trains a few steps, writes its
//! weights, and continues with `--resume`.

mod support;

use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_data::gt::read_inv_depth;
use omnimvs_data::metrics::eval_metrics;
use omnimvs_net::mccnn::{self, McCnnExtractor};
use omnimvs_stereo::{CameraView, SphereProjector, SweepStep, feature_cost_volume};
use support::{constant_guess_mae, read_json, run_ok, synth_dataset};

#[test]
fn sgm_with_the_learned_cost_finds_the_depth() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1", "384x400", 21);
    let out = dir.path().join("mccnn");
    let stdout = run_ok(
        &[
            "sgm",
            data.to_str().unwrap(),
            "--frames",
            "1",
            "--size",
            "80x320",
            "--ndepth",
            "64",
            "--cost",
            "mccnn",
            "--out",
            out.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(stdout.contains("MC-CNN+SGM"), "{stdout}");
    let report = read_json(&out.join("sgm.json"));
    assert_eq!(report["ndepth"].as_u64(), Some(64), "{report}");
    let ds = Dataset::open(&data).unwrap();
    let spec = ds.sweep_spec(80, 320, 45.0, 64).unwrap();
    let truth = ds.eval_truth(1, &spec).unwrap().unwrap();
    let index = read_inv_depth(&out.join("00001_index.tiff")).unwrap();
    let m = eval_metrics(&index.data, &truth, 64).unwrap().reference;
    let constant = constant_guess_mae(&truth, 64);
    assert!(
        m.mae < 0.6 * constant,
        "MC-CNN+SGM MAE {} against the best constant's {constant}",
        m.mae
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

#[test]
fn train_cost_writes_weights_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1..3", "384x400", 23);
    let run = dir.path().join("run");
    let stdout = run_ok(
        &[
            "train",
            "--cost",
            "mccnn",
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
        ],
        &cache,
    );
    assert!(stdout.contains("step     2"), "{stdout}");
    let stdout = run_ok(
        &["train", "--resume", run.to_str().unwrap(), "--steps", "4"],
        &cache,
    );
    assert!(stdout.contains("from step 2"), "{stdout}");
    assert!(stdout.contains("step     4"), "{stdout}");
    let lines = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 2, "{lines}");
    let net = mccnn::load(&run.join("model.safetensors"), &Device::flex()).unwrap();
    assert_eq!(net.config.family, "mccnn");
    // The trained weights drive `sgm --cost-weights FILE`.
    let out = dir.path().join("sgm");
    let stdout = run_ok(
        &[
            "sgm",
            data.to_str().unwrap(),
            "--frames",
            "3",
            "--size",
            "40x160",
            "--ndepth",
            "32",
            "--cost",
            "mccnn",
            "--cost-weights",
            run.join("model.safetensors").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(stdout.contains("wrote 1 frames"), "{stdout}");
}

#[test]
fn sgm_with_the_sweepnet_cost_finds_the_depth() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1", "384x400", 24);
    let out = dir.path().join("sweepnet");
    let stdout = run_ok(
        &[
            "sgm",
            data.to_str().unwrap(),
            "--frames",
            "1",
            "--size",
            "80x320",
            "--ndepth",
            "64",
            "--cost",
            "sweepnet",
            "--median",
            "5",
            "--out",
            out.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(stdout.contains("SweepNet+SGM"), "{stdout}");
    let ds = Dataset::open(&data).unwrap();
    let spec = ds.sweep_spec(80, 320, 45.0, 64).unwrap();
    let truth = ds.eval_truth(1, &spec).unwrap().unwrap();
    let index = read_inv_depth(&out.join("00001_index.tiff")).unwrap();
    let m = eval_metrics(&index.data, &truth, 64).unwrap().reference;
    let constant = constant_guess_mae(&truth, 64);
    assert!(
        m.mae < 0.6 * constant,
        "SweepNet+SGM MAE {} against the best constant's {constant}",
        m.mae
    );
    // Leaving the least confident pixels without an answer: they are NaN, the metrics say
    // how many kept one.
    let out = dir.path().join("sparse");
    let stdout = run_ok(
        &[
            "sgm",
            data.to_str().unwrap(),
            "--frames",
            "1",
            "--size",
            "80x320",
            "--ndepth",
            "64",
            "--min-confidence",
            "0.05",
            "--out",
            out.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(stdout.contains("coverage"), "{stdout}");
    let index = read_inv_depth(&out.join("00001_index.tiff")).unwrap();
    let nan = index.data.iter().filter(|v| v.is_nan()).count();
    assert!(
        nan > 0 && nan < index.data.len(),
        "{nan} pixels without an answer"
    );
    let report = read_json(&out.join("sgm.json"));
    let coverage = report["mean_metrics"]["coverage_pct"].as_f64();
    assert!(coverage.is_some_and(|c| c > 1.0 && c < 100.0), "{report}");
}

#[test]
fn train_sweepnet_writes_weights_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1..3", "384x400", 25);
    let run = dir.path().join("run");
    let args = |steps: &str, stop: &str| -> Vec<String> {
        [
            "train",
            "--cost",
            "sweepnet",
            "--data",
            data.to_str().unwrap(),
            "--out",
            run.to_str().unwrap(),
            "--steps",
            steps,
            "--batch",
            "16",
            "--train-frames",
            "1..2",
            "--val-frames",
            "3..3",
            "--stop-after",
            stop,
        ]
        .map(String::from)
        .to_vec()
    };
    let a = args("4", "2");
    let stdout = run_ok(&a.iter().map(String::as_str).collect::<Vec<_>>(), &cache);
    assert!(stdout.contains("step     2"), "{stdout}");
    let stdout = run_ok(
        &["train", "--resume", run.to_str().unwrap(), "--steps", "4"],
        &cache,
    );
    assert!(stdout.contains("from step 2"), "{stdout}");
    assert!(stdout.contains("step     4"), "{stdout}");
    let lines = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 2, "{lines}");
    let net = omnimvs_net::sweepnet::load(&run.join("model.safetensors"), &Device::flex()).unwrap();
    assert_eq!(net.config.family, "sweepnet");
    // A second run into the same folder is refused; the trained weights drive `sgm`.
    let again = support::omnimvs(&a.iter().map(String::as_str).collect::<Vec<_>>(), &cache);
    let err = support::text(&again.stderr);
    assert!(
        !again.status.success() && err.contains("holds a run already"),
        "{err}"
    );
    let out = dir.path().join("sgm");
    let stdout = run_ok(
        &[
            "sgm",
            data.to_str().unwrap(),
            "--frames",
            "3",
            "--size",
            "40x160",
            "--ndepth",
            "32",
            "--cost",
            "sweepnet",
            "--cost-weights",
            run.join("model.safetensors").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(stdout.contains("wrote 1 frames"), "{stdout}");
}
