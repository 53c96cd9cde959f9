//! `omnimvs synth` end to end, at a tiny image size.

#![allow(clippy::unwrap_used, clippy::expect_used)] // helpers of tests

use std::process::Command;

mod support;
use support::synth_dataset;

fn omnimvs(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_omnimvs"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn synth_writes_a_dataset_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("things");
    let out_s = out.to_str().unwrap();
    let args = [
        "synth", "--kind", "things", "--frames", "1..2", "--out", out_s, "--size", "48x50",
        "--seed", "3",
    ];
    let o = omnimvs(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "config.yaml",
        "synth.json",
        "cam1/00001.png",
        "cam4/00002.png",
        "omnidepth_gt_640/00002.tiff",
        "scene/00001.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let o = omnimvs(&args);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("0 frame(s) rendered"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
}

#[test]
fn synth_hard_is_recorded_and_a_resume_with_another_difficulty_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("hard");
    let out_s = out.to_str().unwrap();
    let args = [
        "synth",
        "--kind",
        "house",
        "--frames",
        "1",
        "--out",
        out_s,
        "--size",
        "48x50",
        "--difficulty",
        "hard",
    ];
    let o = omnimvs(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let settings = std::fs::read_to_string(out.join("synth.json")).unwrap();
    assert!(settings.contains("\"difficulty\": \"hard\""), "{settings}");
    let o = omnimvs(&args[..args.len() - 2]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("difficulty hard there, standard now"),
        "{err}"
    );
    let o = omnimvs(&[&args[..args.len() - 1], &["extreme"]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("standard") && err.contains("hard"),
        "{err}"
    );
}

#[test]
fn synth_rejects_bad_input_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let out_s = out.to_str().unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &["--kind", "rooms", "--frames", "1"],
            "possible values: things, house",
        ),
        (&["--kind", "things", "--frames", "5..2"], "reversed"),
        (
            &["--kind", "things", "--frames", "1", "--rig", "/no/rig.yaml"],
            "/no/rig.yaml",
        ),
        (
            &["--kind", "things", "--frames", "1", "--shard", "3/2"],
            "--shard",
        ),
    ];
    for (extra, want) in cases {
        let mut args = vec!["synth", "--out", out_s, "--size", "48x50"];
        args.extend_from_slice(extra);
        let o = omnimvs(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{args:?}: {err}");
    }
}

/// `eval` and `infer` use the model compiled into the binary, so they work from any folder
/// (here a fresh temporary one, with no `models/` beside it).
#[test]
fn bundled_model_runs_from_any_folder() {
    let dir = tempfile::tempdir().unwrap();
    synth_dataset(dir.path(), "things", "1", "96x100", 5);
    let work = dir.path().join("elsewhere");
    std::fs::create_dir(&work).unwrap();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_omnimvs"))
            .args(args)
            .current_dir(&work)
            .env("OMNIMVS_CACHE_DIR", dir.path().join("cache"))
            .output()
            .unwrap()
    };
    let o = run(&[
        "eval",
        "--data",
        "../things",
        "--method",
        "net",
        "--frames",
        "1",
        "--out",
        "eval",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(work.join("eval/eval.json")).unwrap())
            .unwrap();
    let mae = report["methods"][0]["metrics"]["mae"].as_f64().unwrap();
    assert!(mae.is_finite() && mae > 0.0 && mae < 100.0, "{report}");
    let o = run(&["infer", "../things", "--frames", "1", "--out", "net"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let settings = std::fs::read_to_string(work.join("net/infer.json")).unwrap();
    // The default bundled model (`bundled cascade (models/omnimvs-cascade.safetensors)`: the
    // file is not read, it is compiled in).
    assert!(settings.contains("bundled cascade"), "{settings}");
    assert!(work.join("net/00001_index.tiff").is_file());
}
