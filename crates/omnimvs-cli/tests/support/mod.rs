//! Helpers of the CLI tests that run the built binary on small generated datasets.

// Each test file uses some of these.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use omnimvs_data::gt::EvalTruth;
use omnimvs_eval::metrics::Protocol;

/// Runs `omnimvs args` with its lookup-table cache in `cache`.
pub fn omnimvs(args: &[&str], cache: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_omnimvs"))
        .args(args)
        .env("OMNIMVS_CACHE_DIR", cache)
        .output()
        .expect("run omnimvs")
}

/// Runs `omnimvs args`, asserts that it succeeded and returns its standard output.
pub fn run_ok(args: &[&str], cache: &Path) -> String {
    let o = omnimvs(args, cache);
    assert!(
        o.status.success(),
        "omnimvs {}: {}",
        args.join(" "),
        text(&o.stderr)
    );
    text(&o.stdout)
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A `things` dataset of `frames` (e.g. `1..2`) rendered into `dir/name` with cameras of
/// `size` (e.g. `96x100`: small enough for a debug build) from `seed`.
pub fn synth_dataset(dir: &Path, name: &str, frames: &str, size: &str, seed: u64) -> PathBuf {
    let data = dir.join(name);
    let seed = seed.to_string();
    run_ok(
        &[
            "synth",
            "--kind",
            "things",
            "--frames",
            frames,
            "--out",
            data.to_str().unwrap(),
            "--size",
            size,
            "--seed",
            &seed,
        ],
        &dir.join("cache"),
    );
    data
}

/// Reads a JSON file.
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Width and height of a PNG file.
pub fn png_size(path: &Path) -> (u32, u32) {
    image::image_dimensions(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The mean absolute error (in % of N) of the best constant answer (the median index) over
/// the pixels the reference protocol scores: what a method that ignores the images gets.
pub fn constant_guess_mae(truth: &EvalTruth, ndepth: usize) -> f64 {
    let mut scored: Vec<f32> = (0..truth.gt.index.len())
        .filter(|&i| Protocol::Reference.scores(truth, i))
        .map(|i| truth.gt.index[i])
        .collect();
    scored.sort_by(f32::total_cmp);
    let median = scored[scored.len() / 2];
    let sum: f64 = scored.iter().map(|&g| f64::from((g - median).abs())).sum();
    sum / scored.len() as f64 / ndepth as f64 * 100.0
}
