//! Redraws a run's `curves.png` from its `metrics.jsonl` (e.g. after the plot changed):
//!
//! `cargo run -p omnimvs-train --example redraw_curves -- RUN_DIR/metrics.jsonl OUT.png`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use omnimvs_train::plot::{plot_curves, read_metrics};

fn main() {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [metrics, out] = args.as_slice() else {
        panic!("usage: redraw_curves METRICS.jsonl OUT.png");
    };
    let history = read_metrics(metrics).unwrap();
    plot_curves(&history, out).unwrap();
    println!("{} epochs -> {}", history.len(), out.display());
}
