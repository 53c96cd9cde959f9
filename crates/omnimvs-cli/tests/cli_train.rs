#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! `omnimvs train` end to end, a few steps of the `tiny` preset on a small generated dataset:
//! a run stopped after one epoch and continued with `--resume` ends with the same weights and
//! losses as the run made in one go (even after an attempt whose checkpoint could not be put in
//! place, which leaves the previous checkpoint as it was), and `infer --weights RUN/model.safetensors` reads the
//! weights back and scores the validation frame as the trainer's validation did (with sky, and
//! by the reference's rules). A run records its backend and --resume continues on it. A run started
//! from those weights (`--init`, with frozen batch-norm statistics) validates them before its
//! first step and keeps them as best unless an epoch beats them.

mod support;

use std::path::Path;

use omnimvs_data::gt::read_inv_depth;
use support::{omnimvs, read_json, run_ok, synth_dataset, text};

/// The tensor bytes of a `.safetensors` file (after its 8-byte length and JSON header, whose
/// metadata keys come in no fixed order).
fn tensor_bytes(path: &Path) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    let header = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    bytes[8 + header..].to_vec()
}

/// Each epoch's record of metrics.jsonl without its timings.
fn epochs(run: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(run.join("metrics.jsonl"))
        .unwrap()
        .lines()
        .map(|line| {
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            serde_json::json!({
                "epoch": v["epoch"], "lr": v["lr"], "train_loss": v["train_loss"],
                "steps": v["steps"], "val_loss": v["val_loss"], "val": v["val"],
                "val_reference": v["val_reference"],
            })
        })
        .collect()
}

#[test]
fn train_resumes_exactly_and_infer_reads_the_weights() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1..3", "96x100", 7);
    let data_s = data.to_str().unwrap();
    let train = |run: &Path, extra: &[&str]| {
        let mut args = vec![
            "train",
            "--data",
            data_s,
            "--preset",
            "tiny",
            "--out",
            run.to_str().unwrap(),
            "--epochs",
            "2",
            "--max-steps",
            "2",
            "--max-val-frames",
            "1",
            "--rotations",
            "1",
            "--train-frames",
            "1..2",
            "--val-frames",
            "3",
        ];
        args.extend(extra);
        run_ok(&args, &cache)
    };

    // One epoch, then --resume to the end.
    let resumed = dir.path().join("resumed");
    let stdout = train(&resumed, &["--stop-after", "1", "--lr", "0.002"]);
    assert!(stdout.contains("epochs 1..2 of 2"), "{stdout}");
    assert_eq!(epochs(&resumed).len(), 1);
    let config = read_json(&resumed.join("train_config.json"));
    assert_eq!(
        (
            config["net"]["out_height"].as_u64(),
            config["net"]["out_width"].as_u64()
        ),
        (Some(32), Some(128)),
        "the tiny preset's grid: {config}"
    );
    // Without --lr-low the last epochs' rate is a tenth of --lr (never above it).
    assert_eq!(config["lr"].as_f64(), Some(0.002), "{config}");
    assert!(
        (config["lr_low"].as_f64().unwrap() - 0.0002).abs() < 1e-12,
        "{config}"
    );

    // The run records its backend, and --resume without --backend continues on it: a run
    // recorded as started on libtorch is not silently continued on the CPU (this default build
    // has no libtorch, so it refuses and names the feature), a recorded name that is not a
    // backend is refused naming the file and the field, and neither attempt touches the run.
    let backend_file = resumed.join("backend.txt");
    assert!(stdout.contains("on cpu:"), "{stdout}");
    assert_eq!(std::fs::read_to_string(&backend_file).unwrap(), "cpu\n");
    let latest = std::fs::read(resumed.join("latest.json")).unwrap();
    for (recorded, expected) in [
        ("libtorch-cuda:0\n", "--features libtorch"),
        ("gpu-9000\n", "field `backend`"),
    ] {
        std::fs::write(&backend_file, recorded).unwrap();
        let o = omnimvs(&["train", "--resume", resumed.to_str().unwrap()], &cache);
        let stderr = text(&o.stderr);
        assert!(!o.status.success(), "{recorded}: {stderr}");
        assert!(stderr.contains(expected), "{recorded}: {stderr}");
        assert!(
            recorded.starts_with("libtorch") || stderr.contains("backend.txt"),
            "{stderr}"
        );
        assert_eq!(std::fs::read(resumed.join("latest.json")).unwrap(), latest);
        assert_eq!(epochs(&resumed).len(), 1);
    }
    std::fs::write(&backend_file, "cpu\n").unwrap();

    // A number of epochs the run cannot take is refused before it is written: the run's
    // configuration stays as it was.
    let config_text = std::fs::read_to_string(resumed.join("train_config.json")).unwrap();
    let o = omnimvs(
        &[
            "train",
            "--resume",
            resumed.to_str().unwrap(),
            "--epochs",
            "0",
        ],
        &cache,
    );
    let stderr = text(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(stderr.contains("epochs"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(resumed.join("train_config.json")).unwrap(),
        config_text
    );
    assert_eq!(epochs(&resumed).len(), 1);

    // A checkpoint that cannot be put in place (a file stands where epoch 2's folder goes)
    // fails the run and leaves epoch 1's checkpoint and the pointer to it as they were.
    let checkpoint = resumed.join("checkpoints/epoch-0001");
    let files = ["model.bpk", "optim.bpk", "state.json"];
    let before: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(checkpoint.join(f)).unwrap())
        .collect();
    let latest = std::fs::read(resumed.join("latest.json")).unwrap();
    let blocker = resumed.join("checkpoints/epoch-0002");
    std::fs::write(&blocker, b"not a folder").unwrap();
    let o = omnimvs(&["train", "--resume", resumed.to_str().unwrap()], &cache);
    assert!(
        !o.status.success(),
        "a blocked checkpoint must fail the run"
    );
    assert!(
        text(&o.stderr).contains("epoch-0002"),
        "{}",
        text(&o.stderr)
    );
    assert_eq!(std::fs::read(resumed.join("latest.json")).unwrap(), latest);
    for (f, bytes) in files.iter().zip(&before) {
        assert_eq!(&std::fs::read(checkpoint.join(f)).unwrap(), bytes, "{f}");
    }
    std::fs::remove_file(&blocker).unwrap();

    // Resumed from there (after the failed attempt), the run ends as the straight one below;
    // --backend overrides the recorded backend and is recorded in its place, and so does
    // --loader-threads.
    std::fs::write(&backend_file, "libtorch\n").unwrap();
    let stdout = run_ok(
        &[
            "train",
            "--resume",
            resumed.to_str().unwrap(),
            "--backend",
            "cpu",
            "--loader-threads",
            "2",
        ],
        &cache,
    );
    assert!(stdout.contains("epochs 2..2 of 2"), "{stdout}");
    assert_eq!(std::fs::read_to_string(&backend_file).unwrap(), "cpu\n");
    let config = read_json(&resumed.join("train_config.json"));
    assert_eq!(config["loader_threads"].as_u64(), Some(2), "{config}");

    // The same run in one go, its samples prepared by three threads: the same samples in
    // the same order.
    let straight = dir.path().join("straight");
    train(&straight, &["--lr", "0.002", "--loader-threads", "3"]);
    let (a, b) = (epochs(&resumed), epochs(&straight));
    assert_eq!(a.len(), 2);
    assert_eq!(
        a, b,
        "the resumed run's losses differ from the straight run's"
    );
    assert!(a[1]["train_loss"].as_f64().unwrap().is_finite());
    assert!(
        tensor_bytes(&resumed.join("model.safetensors"))
            == tensor_bytes(&straight.join("model.safetensors")),
        "the resumed run's weights differ from the straight run's"
    );

    // infer reads the weights back: the tiny grid, and the validation frame's MAE as the
    // trainer measured it after the last epoch.
    let out = dir.path().join("infer");
    let weights = resumed.join("model.safetensors");
    run_ok(
        &[
            "infer",
            data_s,
            "--weights",
            weights.to_str().unwrap(),
            "--frames",
            "3",
            "--out",
            out.to_str().unwrap(),
        ],
        &cache,
    );
    for file in ["00003.tiff", "00003_index.tiff", "00003_entropy.tiff"] {
        let map = read_inv_depth(&out.join(file)).unwrap();
        assert_eq!((map.width, map.height), (128, 32), "{file}");
        assert!(map.data.iter().all(|v| v.is_finite()), "{file}");
    }
    // Both protocols: the trainer's `val` scores sky as index 0 (what it trains on), its
    // `val_reference` as the reference does; infer's `mean` is the reference's.
    let metrics = read_json(&out.join("metrics.json"));
    for (trainer_key, infer_key) in [("val_reference", "mean"), ("val", "mean_with_sky")] {
        let infer_mae = metrics[infer_key]["mae"].as_f64().unwrap();
        let val_mae = a[1][trainer_key]["mae"].as_f64().unwrap();
        assert!(
            (infer_mae - val_mae).abs() < 1e-3,
            "infer {infer_key} MAE {infer_mae}, the trainer's {trainer_key} MAE {val_mae}"
        );
    }
    let val_mae = a[1]["val"]["mae"].as_f64().unwrap();

    // Fine-tuning from those weights: they are validated before the first step (the same MAE
    // as the trainer's last validation and infer's), and best.safetensors holds whichever of
    // them and the epoch validated better.
    let tuned = dir.path().join("tuned");
    let stdout = train(
        &tuned,
        &[
            "--init",
            weights.to_str().unwrap(),
            "--lr",
            "0.05",
            "--frozen-norm-stats",
            "on",
            "--select-by",
            "reference",
        ],
    );
    assert!(stdout.contains("start (--init weights"), "{stdout}");
    assert!(stdout.contains("batch-norm statistics frozen"), "{stdout}");
    assert_eq!(
        read_json(&tuned.join("train_config.json"))["frozen_norm_stats"].as_bool(),
        Some(true)
    );
    let start_mae = read_json(&tuned.join("start.json"))["val"]["mae"]
        .as_f64()
        .unwrap();
    assert!(
        (start_mae - val_mae).abs() < 1e-6,
        "start.json MAE {start_mae}, the weights' validation MAE {val_mae}"
    );
    assert_eq!(
        read_json(&tuned.join("train_config.json"))["select_by"].as_str(),
        Some("reference")
    );
    // The best epoch is picked by the reference protocol's MAE (--select-by reference).
    let start_mae = read_json(&tuned.join("start.json"))["val_reference"]["mae"]
        .as_f64()
        .unwrap();
    let maes: Vec<f64> = epochs(&tuned)
        .iter()
        .map(|e| e["val_reference"]["mae"].as_f64().unwrap())
        .collect();
    assert!(stdout.contains("reference protocol"), "{stdout}");
    let best = tensor_bytes(&tuned.join("best.safetensors"));
    if maes[1] < start_mae.min(maes[0]) {
        assert!(best == tensor_bytes(&tuned.join("model.safetensors")));
        assert!(stdout.contains("best epoch 2"), "{stdout}");
    } else if maes[0] < start_mae {
        assert!(stdout.contains("best epoch 1"), "{stdout}");
    } else {
        assert!(
            best == tensor_bytes(&weights),
            "best must stay the --init weights"
        );
        assert!(stdout.contains("no epoch beat them"), "{stdout}");
    }
}

#[test]
fn a_run_that_cannot_start_says_why_and_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1..2", "96x100", 11);
    let missing_init = dir.path().join("no-such-weights.safetensors");
    let missing_data = dir.path().join("no-such-dataset");
    // What is missing, the data folder given, the extra arguments, and the name the error
    // must give (for weights, the configuration read first beside them).
    for (what, data, extra, named) in [
        (
            "the --init weights",
            &data,
            vec!["--init", missing_init.to_str().unwrap()],
            "no-such-weights",
        ),
        ("the dataset", &missing_data, vec![], "no-such-dataset"),
    ] {
        let run = dir.path().join("run");
        let mut args = vec![
            "train",
            "--data",
            data.to_str().unwrap(),
            "--preset",
            "tiny",
            "--out",
            run.to_str().unwrap(),
            "--epochs",
            "1",
            "--max-steps",
            "1",
        ];
        args.extend(extra);
        let o = omnimvs(&args, &cache);
        assert!(!o.status.success(), "{what}: {}", text(&o.stdout));
        let stderr = text(&o.stderr);
        assert!(stderr.contains(named), "{what}: {stderr}");
        assert!(
            !run.exists(),
            "{what}: a failed start left {}",
            run.display()
        );
    }
}

/// The cascade's network options of a new run: values the network cannot take, and the
/// options given to another preset, are refused before any folder is made.
#[test]
fn cascade_options_are_checked_and_belong_to_the_cascade() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let run = dir.path().join("run");
    for (preset, flag, value, expected) in [
        (
            "cascade",
            "--stage-intervals",
            "0,1",
            "two positive index spacings",
        ),
        (
            "cascade",
            "--stage-intervals",
            "2.5",
            "two positive index spacings",
        ),
        ("cascade", "--stage-intervals", "a,1", "stage-intervals"),
        (
            "tiny",
            "--stage-intervals",
            "2.5,1.5",
            "options of --preset cascade",
        ),
        (
            "cascade",
            "--coarse-feature-channels",
            "20",
            "8 groups must divide 20",
        ),
        ("cascade", "--coarse-feature-channels", "128", "at most 64"),
        (
            "cascade",
            "--coarse-cue-oversample",
            "3",
            "cascade.coarse_cue_oversample",
        ),
        (
            "cascade",
            "--coarse-cue-depths",
            "2",
            "cascade.coarse_cue_depths",
        ),
        (
            "tiny",
            "--coarse-cue-depths",
            "3",
            "options of --preset cascade",
        ),
        (
            "tiny",
            "--coarse-cue-oversample",
            "2",
            "options of --preset cascade",
        ),
        (
            "tiny",
            "--coarse-feature-channels",
            "32",
            "options of --preset cascade",
        ),
        // The aggregated cue aggregates the photometric cue, off in the preset.
        (
            "cascade",
            "--coarse-cue-sgm",
            "on",
            "cascade.coarse_cue_sgm",
        ),
        (
            "tiny",
            "--coarse-cue-sgm",
            "on",
            "options of --preset cascade",
        ),
    ] {
        let o = omnimvs(
            &[
                "train",
                "--data",
                dir.path().to_str().unwrap(),
                "--preset",
                preset,
                flag,
                value,
                "--out",
                run.to_str().unwrap(),
            ],
            &cache,
        );
        assert!(!o.status.success(), "{flag} {value}: {}", text(&o.stdout));
        let stderr = text(&o.stderr);
        assert!(stderr.contains(expected), "{flag} {value}: {stderr}");
        assert!(!run.exists(), "{flag} {value}: a refused run left a folder");
    }
}
