#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! `omnimvs finetune` end to end on a small trial (three-camera Kalibr rig, 96x100 images, one
//! step): it renders the data, scores the bundled network and ZNCC+SGM before and the
//! fine-tuned weights after on the same held-out frames, keeps the best weights as
//! `model.safetensors`, and continues a finished run as a no-op; options that contradict the
//! run, a missing rig and the pose unit are refused with the option named, leaving no folder.

mod support;

use std::path::{Path, PathBuf};

use support::{omnimvs, read_json, run_ok, text};

fn rig() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/rigs/eucm-3cam/camchain.yaml")
}

#[test]
fn finetune_renders_trains_and_reports_before_and_after_and_continues() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let run = dir.path().join("run");
    let run_s = run.to_str().unwrap();
    let rig = rig();
    let rig_s = rig.to_str().unwrap();
    let first = run_ok(
        &[
            "--rig-frame",
            "fitted",
            "finetune",
            "--rig",
            rig_s,
            "--out",
            run_s,
            "--frames",
            "2",
            "--test-frames",
            "1",
            "--epochs",
            "1",
            "--steps",
            "1",
            "--size",
            "96x100",
        ],
        &cache,
    );
    assert!(first.contains("(3 cameras)"), "{first}");
    for name in [
        "train-things",
        "train-house",
        "train-things-hard",
        "train-house-hard",
        "test-things",
        "test-house",
    ] {
        assert!(
            run.join("data").join(name).join("config.yaml").is_file(),
            "{name}"
        );
    }
    // Before: the bundled network and ZNCC+SGM; after: the fine-tuned weights; both sets.
    let report = read_json(&run.join("report.json"));
    let rows = report["rows"].as_array().unwrap();
    let names: Vec<(String, String)> = rows
        .iter()
        .map(|r| {
            (
                r["set"].as_str().unwrap().to_string(),
                r["method"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    for set in ["things", "house"] {
        for method in ["the bundled network", "ZNCC+SGM", "fine-tuned"] {
            assert!(
                names.contains(&(set.to_string(), method.to_string())),
                "{set} {method}: {names:?}"
            );
        }
    }
    for r in rows {
        let mae = r["metrics"]["mae"].as_f64().unwrap();
        assert!(mae.is_finite() && mae > 0.0, "{r}");
    }
    assert!(first.contains("| house | fine-tuned |"), "{first}");
    // The weights kept are the run's best, with their configuration.
    assert_eq!(
        std::fs::read(run.join("model.safetensors")).unwrap(),
        std::fs::read(run.join("train/best.safetensors")).unwrap()
    );
    assert!(run.join("model.json").is_file());
    let plan = read_json(&run.join("finetune.json"));
    assert_eq!(
        Path::new(plan["rig"].as_str().unwrap()),
        rig.canonicalize().unwrap()
    );
    assert_eq!(plan["rig_frame"], "fitted");

    // Continuing a finished run does nothing new and reports the same figures.
    let again = run_ok(&["finetune", "--out", run_s], &cache);
    assert!(!again.contains("rendered in") || again.contains("0 frame(s) rendered"));
    assert!(!again.contains("epoch   1"), "{again}");
    assert_eq!(read_json(&run.join("report.json")), report);

    // Options that contradict the run are named.
    let o = omnimvs(&["finetune", "--out", run_s, "--steps", "5"], &cache);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.contains("--steps") && err.contains("finetune.json"),
        "{err}"
    );

    // A new folder needs a rig, and a rig that cannot be read leaves no folder.
    let fresh = dir.path().join("fresh");
    let o = omnimvs(&["finetune", "--out", fresh.to_str().unwrap()], &cache);
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("--rig"), "{}", text(&o.stderr));
    let missing = dir.path().join("missing.yaml");
    let o = omnimvs(
        &[
            "finetune",
            "--rig",
            missing.to_str().unwrap(),
            "--out",
            fresh.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("missing.yaml"),
        "{}",
        text(&o.stderr)
    );
    assert!(!fresh.exists());
    let o = omnimvs(
        &[
            "--pose-unit",
            "mm",
            "finetune",
            "--rig",
            rig_s,
            "--out",
            fresh.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("--pose-unit"),
        "{}",
        text(&o.stderr)
    );
    assert!(!fresh.exists());
}
