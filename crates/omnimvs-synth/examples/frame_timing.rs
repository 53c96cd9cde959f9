//! Times full frames with the published rig (4 x 768x800 fisheyes + 320x640
//! ground truth): wall time and process CPU time per frame, for several
//! samples per pixel. On a shared machine the CPU time is the stable figure;
//! the wall time on 2 free cores is about CPU / 2 (rows render in parallel).
//!
//! ```text
//! cargo run --release -p omnimvs-synth --example frame_timing -- 3 1,2,4
//! ```
//! (frames per setting, samples per pixel list). Linux only (reads
//! `/proc/self/stat` for the CPU time).

use std::time::Instant;

use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::dataset::{GT_HEIGHT, GT_PHI_DEG, GT_WIDTH, render_scene};
use omnimvs_synth::rig::{preset_rig, rig_radius_m};
use omnimvs_synth::{GenParams, SceneKind, generate};

/// User + system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name (which is in parentheses).
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // utime and stime are fields 14 and 15 of the stat line (11 and 12 here).
    (ticks(11) + ticks(12)) / 100.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frames: u32 = args.first().map_or(Ok(3), |s| s.parse())?;
    let spps: Vec<u32> = args
        .get(1)
        .map_or("1,2,4", String::as_str)
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let source = preset_rig()?;
    let params = GenParams::new(source.min_depth_m, rig_radius_m(&source.rig));
    let grid = EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG)?;
    println!("threads: {}", rayon::current_num_threads());
    println!("kind    spp  wall s/frame  cpu s/frame  cpu/2 (2-core estimate)");
    for kind in [SceneKind::Things, SceneKind::House] {
        for &spp in &spps {
            let (t0, c0) = (Instant::now(), cpu_seconds());
            for frame in 1..=frames {
                let scene = generate(kind, 0, frame, &params)?;
                std::hint::black_box(render_scene(&scene, &[], &source.rig, spp, &grid)?);
            }
            let wall = t0.elapsed().as_secs_f64() / f64::from(frames);
            let cpu = (cpu_seconds() - c0) / f64::from(frames);
            println!(
                "{:7} {spp:3}  {wall:12.3}  {cpu:11.3}  {:.3}",
                kind.name(),
                cpu / 2.0
            );
        }
    }
    Ok(())
}
