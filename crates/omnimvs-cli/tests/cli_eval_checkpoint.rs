#![allow(clippy::unwrap_used, clippy::expect_used)]
//! `omnimvs eval --weights CHECKPOINT.pt`: a reference PyTorch checkpoint carries its channels
//! and cameras but not its grid, which `--preset` gives (default `paper`, as `infer`'s). The
//! bug this guards against: `eval` sized every checkpoint as `tiny`, so a reference network
//! was evaluated at 32x128, N = 64 instead of the paper's 160x640, N = 192.

mod support;

use std::path::Path;

use support::{read_json, run_ok, synth_dataset};

/// The reference checkpoint of the PyTorch parity fixtures (CH 4, 4 cameras, random weights).
fn checkpoint() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../omnimvs-net/tests/fixtures/parity/parity.pt")
        .to_str()
        .unwrap()
        .to_string()
}

/// (height, width, N) of the grid the network answered at, and whether it was resampled.
fn native_grid(report: &serde_json::Value) -> ((u64, u64, u64), bool) {
    let net = &report["methods"][0];
    assert_eq!(net["method"], "net", "{report}");
    let n = &net["native"];
    (
        (
            n["height"].as_u64().unwrap(),
            n["width"].as_u64().unwrap(),
            n["ndepth"].as_u64().unwrap(),
        ),
        net["resampled"].as_bool().unwrap(),
    )
}

#[test]
fn a_reference_checkpoint_is_evaluated_at_the_papers_grid() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1", "96x100", 5);
    let pt = checkpoint();
    let eval = |out: &Path, preset: Option<&str>, size: &str, ndepth: &str| {
        let mut args = vec![
            "eval",
            "--data",
            data.to_str().unwrap(),
            "--method",
            "net",
            "--weights",
            &pt,
            "--frames",
            "1",
            "--size",
            size,
            "--ndepth",
            ndepth,
            "--out",
            out.to_str().unwrap(),
        ];
        if let Some(preset) = preset {
            args.extend(["--preset", preset]);
        }
        run_ok(&args, &cache);
        read_json(&out.join("eval.json"))
    };

    // The default preset is the paper's: the network answers at 160x640, N = 192; scored at
    // that grid nothing is resampled.
    let report = eval(&dir.path().join("paper"), None, "160x640", "192");
    assert_eq!(native_grid(&report), ((160, 640, 192), false), "{report}");
    let mae = report["methods"][0]["metrics"]["mae"].as_f64().unwrap();
    assert!((0.0..=100.0).contains(&mae), "{report}");

    // --preset tiny sizes the same checkpoint at the tiny grid, resampled to the evaluation's.
    let report = eval(&dir.path().join("tiny"), Some("tiny"), "40x160", "48");
    assert_eq!(native_grid(&report), ((32, 128, 64), true), "{report}");
}
