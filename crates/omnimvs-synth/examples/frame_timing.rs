//! Times full frames with the published rig (4 x 768x800 fisheyes + 320x640
//! ground truth): wall time and process CPU time per frame, for several
//! samples per pixel. On a shared machine the CPU time is the stable figure;
//! the wall time on 2 free cores is about CPU / 2 (rows render in parallel).
//!
//! ```text
//! cargo run --release -p omnimvs-synth --example frame_timing -- 3 1,2,4 standard,hard
//! ```
//! (frames per setting, samples per pixel list, difficulties; `hard` frames
//! include the camera effects on the images). Linux only (reads
//! `/proc/self/stat` for the CPU time).

use std::time::Instant;

use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::camera_effects::{CameraEffects, apply_all, auto_expose};
use omnimvs_synth::dataset::{GT_HEIGHT, GT_PHI_DEG, GT_WIDTH, render_scene};
use omnimvs_synth::rig::{preset_rig, rig_radius_m};
use omnimvs_synth::{Difficulty, GenParams, SceneKind, generate};

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
    let difficulties: Vec<Difficulty> = args
        .get(2)
        .map_or("standard", String::as_str)
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let source = preset_rig()?;
    let grid = EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG)?;
    println!("threads: {}", rayon::current_num_threads());
    println!("kind    difficulty  spp  wall s/frame  cpu s/frame  cpu/2 (2-core estimate)");
    for &difficulty in &difficulties {
        let mut params = GenParams::new(source.min_depth_m, rig_radius_m(&source.rig));
        params.difficulty = difficulty;
        for kind in [SceneKind::Things, SceneKind::House] {
            for &spp in &spps {
                let (t0, c0) = (Instant::now(), cpu_seconds());
                for frame in 1..=frames {
                    let scene = generate(kind, 0, frame, &params)?;
                    let (mut images, gt) = render_scene(&scene, &[], &source.rig, spp, &grid)?;
                    if difficulty.is_hard() {
                        let mut effects = CameraEffects::draw(0, frame, source.rig.cameras.len());
                        auto_expose(&mut effects, &images);
                        apply_all(&effects, &source.rig.cameras, &mut images)?;
                    }
                    std::hint::black_box((images, gt));
                }
                let wall = t0.elapsed().as_secs_f64() / f64::from(frames);
                let cpu = (cpu_seconds() - c0) / f64::from(frames);
                println!(
                    "{:7} {:10}  {spp:3}  {wall:12.3}  {cpu:11.3}  {:.3}",
                    kind.name(),
                    difficulty.name(),
                    cpu / 2.0
                );
            }
        }
    }
    Ok(())
}
