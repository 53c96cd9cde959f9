#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The whole method at the paper's size on generated rooms (`omnimvs-synth`), with stage
//! timings, peak memory and metrics.
//!
//! `cargo run --release -p omnimvs-stereo --example full_size -- [frames] [scale] [HxW] [N] [every-other]`
//! (defaults: 2 frames, full-size 768x800 images, 160x640, N = 192).

#[path = "../tests/support/scenes.rs"]
mod scenes;

use omnimvs_data::gt::ground_truth_index;
use omnimvs_data::metrics::frame_metrics;

use omnimvs_stereo::{SgmParams, SphericalStereo, SweepStep};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use scenes::{Rendered, published_rig, room};

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// CPU time (user + system) of the whole process so far, seconds: on a
/// shared machine the wall time depends on the other processes, this does not.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = s
                .rsplit_once(')')?
                .1
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ");
            let f: Vec<f64> = rest.split(' ').filter_map(|v| v.parse().ok()).collect();
            // After the command name: state, ppid, ... utime is field 14 overall.
            Some((f[10] + f[11]) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frames: u64 = args.first().map_or(2, |s| s.parse().unwrap());
    let scale: f64 = args.get(1).map_or(1.0, |s| s.parse().unwrap());
    let (h, w) = args.get(2).map_or((160, 640), |s| {
        let (a, b) = s.split_once('x').unwrap();
        (a.parse().unwrap(), b.parse().unwrap())
    });
    let nd: usize = args.get(3).map_or(192, |s| s.parse().unwrap());
    let sweep = if args.get(4).is_some_and(|s| s == "every-other") {
        SweepStep::EveryOther
    } else {
        SweepStep::All
    };
    let rig = published_rig(scale);
    let grid = EquirectGrid::new(h, w, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(nd, 1.0).unwrap();
    let params = SgmParams {
        sweep,
        ..SgmParams::default()
    };
    let t = std::time::Instant::now();
    let stereo = SphericalStereo::new(&rig, grid, hyps, params).unwrap();
    println!(
        "{} threads; setup {:.3} s",
        rayon::current_num_threads(),
        t.elapsed().as_secs_f64()
    );
    println!("frame | warp s | cost s | aggregation s | wta s | total s | CPU s | MAE | >3 %");
    for k in 0..frames {
        let frame = Rendered::new(&room(&rig, 2000 + k), &rig);
        let gt = ground_truth_index(&frame.inverse_depth(&grid), &hyps);
        let cpu0 = cpu_s();
        let out = stereo.compute(&frame.images, None).unwrap();
        let cpu = cpu_s() - cpu0;
        let m = frame_metrics(&out.index.index, &gt, nd).unwrap();
        let t = out.timings;
        println!(
            "{k} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {cpu:.2} | {:.2} | {:.2}",
            t.warp_s, t.cost_s, t.aggregation_s, t.wta_s, t.total_s, m.mae, m.over3_pct
        );
    }
    println!("peak RSS {:.0} MB", peak_rss_mb());
}
