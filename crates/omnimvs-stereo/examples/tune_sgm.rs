#![allow(clippy::unwrap_used, clippy::expect_used)]
//! Tunes the SGM penalties on generated validation rooms (`omnimvs-synth` houses) (seeds 1000 and up,
//! never used by the tests) and prints the metrics of every (P1, P2) pair,
//! with the best constant guess for comparison.
//!
//! `cargo run --release -p omnimvs-stereo --example tune_sgm -- [frames] [scale] [HxW] [N]`
//! (defaults: 4 frames, images at 0.5 scale, 80x320, N = 96).

#[path = "../tests/support/scenes.rs"]
mod scenes;

use omnimvs_data::gt::ground_truth_index;
use omnimvs_data::metrics::{Metrics, frame_metrics, mean_metrics};

use omnimvs_stereo::{SgmParams, SphericalStereo, winner_take_all};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use scenes::{Rendered, published_rig, room};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frames: u64 = args.first().map_or(4, |s| s.parse().unwrap());
    let scale: f64 = args.get(1).map_or(0.5, |s| s.parse().unwrap());
    let (h, w) = args.get(2).map_or((80, 320), |s| {
        let (a, b) = s.split_once('x').unwrap();
        (a.parse().unwrap(), b.parse().unwrap())
    });
    let nd: usize = args.get(3).map_or(96, |s| s.parse().unwrap());
    let rig = published_rig(scale);
    let grid = EquirectGrid::new(h, w, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(nd, 1.0).unwrap();
    let base = SphericalStereo::new(&rig, grid, hyps, SgmParams::default()).unwrap();
    let mut data = Vec::new();
    for k in 0..frames {
        let frame = Rendered::new(&room(&rig, 1000 + k), &rig);
        let gt = ground_truth_index(&frame.inverse_depth(&grid), &hyps);
        let (cost, t) = base.cost_volume(&frame.images, None).unwrap();
        eprintln!("frame {k}: cost volume in {:.2} s", t.warp_s + t.cost_s);
        data.push((cost, gt));
    }
    // The best constant guess: the mean ground-truth index over all frames.
    let all: Vec<f32> = data
        .iter()
        .flat_map(|(_, g)| {
            g.index
                .iter()
                .zip(&g.valid)
                .filter(|(_, v)| **v)
                .map(|(i, _)| *i)
        })
        .collect();
    let mut sorted = all.clone();
    sorted.sort_by(f32::total_cmp);
    let median = sorted[sorted.len() / 2];
    let constant: Vec<Metrics> = data
        .iter()
        .map(|(_, g)| frame_metrics(&vec![median; g.index.len()], g, nd).unwrap())
        .collect();
    println!("{}", Metrics::MARKDOWN_HEADER);
    println!(
        "{}",
        mean_metrics(&constant)
            .unwrap()
            .markdown_row(&format!("constant n = {median:.1}"))
    );
    let evaluate = |p1: f32, p2: f32| {
        let params = SgmParams {
            p1,
            p2,
            ..SgmParams::default()
        };
        let m: Vec<Metrics> = data
            .iter()
            .map(|(cost, g)| {
                let (agg, _) = omnimvs_stereo::aggregate(cost, &params).unwrap();
                frame_metrics(&winner_take_all(&agg).index, g, nd).unwrap()
            })
            .collect();
        mean_metrics(&m).unwrap()
    };
    println!("{}", evaluate(0.0, 0.0).markdown_row("ZNCC only (no SGM)"));
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for &p1 in &[0.01f32, 0.02, 0.05, 0.1, 0.2] {
        for &p2 in &[0.2f32, 0.4, 0.6, 1.0, 1.5, 2.0, 3.0] {
            if p2 < p1 {
                continue;
            }
            let m = evaluate(p1, p2);
            println!("{}", m.markdown_row(&format!("P1 = {p1}, P2 = {p2}")));
            if m.mae < best.0 {
                best = (m.mae, p1, p2);
            }
        }
    }
    println!("\nbest MAE {:.3}: P1 = {}, P2 = {}", best.0, best.1, best.2);
}
