#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! `omnimvs eval` on frames without ground truth scores how well each depth map explains the
//! images (the cross-camera photometric difference), beside a constant depth: on the real
//! `itbt_sample` the figures are those of the independent NumPy reading
//! (`scripts/photometric_golden/make_photometric_golden.py`), and on generated data
//! (`--photometric`) ZNCC+SGM's depth explains the images better than a constant depth.

mod support;

use std::path::{Path, PathBuf};

use support::{read_json, run_ok, synth_dataset};

fn itbt() -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/itbt_sample");
    assert!(
        path.join("config.yaml").is_file(),
        "this test needs the real sample {} (../shared beside the repository)",
        path.display()
    );
    path
}

/// Each row's `(method, value of the first frame)`.
fn rows(out: &Path) -> Vec<(String, f64)> {
    let report = read_json(&out.join("eval.json"));
    report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["method"].as_str().unwrap().to_string(),
                m["per_frame"][0][1].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn real_frames_are_scored_by_photometric_difference_as_the_numpy_reading_scores_them() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("eval");
    let text = run_ok(
        &[
            "eval",
            "--data",
            itbt().to_str().unwrap(),
            "--frames",
            "1",
            "--method",
            "sgm",
            "--out",
            out.to_str().unwrap(),
        ],
        &dir.path().join("cache"),
    );
    assert!(text.contains("photometric difference"), "{text}");
    let rows = rows(&out);
    assert_eq!(rows[0].0, "ZNCC+SGM");
    assert_eq!(rows[1].0, "a constant 3 m");
    // make_photometric_golden.py on this ZNCC+SGM map: 0.13980946685955245 and, for a
    // constant 3 m, 0.19175727033170414.
    assert!((rows[0].1 - 0.139_809_466_86).abs() < 1e-6, "{rows:?}");
    assert!((rows[1].1 - 0.191_757_270_33).abs() < 1e-6, "{rows:?}");
}

#[test]
fn on_generated_data_the_classical_depth_explains_the_images_better_than_a_constant_one() {
    let dir = tempfile::tempdir().unwrap();
    let data = synth_dataset(dir.path(), "things", "1", "192x200", 3);
    let out = dir.path().join("eval");
    run_ok(
        &[
            "eval",
            "--data",
            data.to_str().unwrap(),
            "--frames",
            "1",
            "--method",
            "sgm",
            "--photometric",
            "--size",
            "64x256",
            "--ndepth",
            "64",
            "--out",
            out.to_str().unwrap(),
        ],
        &dir.path().join("cache"),
    );
    let rows = rows(&out);
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert!(rows[0].1 < rows[1].1, "{rows:?}");
}
