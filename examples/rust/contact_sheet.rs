//! Renders one synthetic `things` frame and one `house` frame through the published rig,
//! without writing a dataset, and saves a contact sheet of each: the four fisheye images
//! (reduced 4x) above the exact ground-truth inverse depth in colour (turbo, 0 to the nearest
//! sphere's 1/1.65 m).
//!
//! ```text
//! cargo run --release -p omnimvs-examples --example contact_sheet -- OUT [THINGS HOUSE SPP [hard]]
//! ```
//!
//! OUT is the output folder (`synth_things.png`, `synth_house.png`); THINGS and HOUSE are
//! the frames to render (default 2 and 3), SPP the samples per pixel (default 1), and `hard`
//! makes harder scenes with camera effects (gain, gamma, vignetting, blur, noise;
//! `synth_things_hard.png`, `synth_house_hard.png`). Seed 0.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::camera_effects::{CameraEffects, apply_all, auto_expose};
use omnimvs_synth::contact::contact_sheet;
use omnimvs_synth::dataset::{GT_HEIGHT, GT_PHI_DEG, GT_WIDTH, render_scene};
use omnimvs_synth::rig::{preset_rig, rig_radius_m};
use omnimvs_synth::{Difficulty, GenParams, SceneKind, generate};

const USAGE: &str = "usage: contact_sheet OUT [THINGS HOUSE SPP [hard]]

Renders `things` frame THINGS (default 2) and `house` frame HOUSE (default 3) of the published
rig at SPP samples per pixel (default 1) and writes their contact sheets into OUT; `hard`:
harder scenes and camera effects.";

/// Seed of the scenes: the same seed and frame give the same scene.
const SEED: u64 = 0;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (out, rest) = match args.as_slice() {
        [out, rest @ ..] if matches!(rest.len(), 0 | 3 | 4) => (out, rest),
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let number = |k: usize, default: u32, what: &str| -> Result<u32> {
        rest.get(k).map_or(Ok(default), |s| {
            s.parse()
                .with_context(|| format!("{what}: expected a number, found {s:?}"))
        })
    };
    let things_frame = number(0, 2, "THINGS")?;
    let house_frame = number(1, 3, "HOUSE")?;
    let spp = number(2, 1, "SPP")?;
    let out = Path::new(out);
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;

    // The published rig (four 220-degree fisheyes, 768x800) and its minimum depth; scenes are
    // generated to fit around a rig of its size.
    let source = preset_rig()?;
    let mut params = GenParams::new(source.min_depth_m, rig_radius_m(&source.rig));
    params.difficulty = rest
        .get(3)
        .map_or(Ok(Difficulty::Standard), |s| s.parse())?;
    // The ground truth's grid: the datasets' 320x640 panorama over all latitudes.
    let grid = EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG)?;
    for (kind, frame) in [
        (SceneKind::Things, things_frame),
        (SceneKind::House, house_frame),
    ] {
        let t0 = Instant::now();
        // A scene description (objects, textures, lights), then the images of every camera
        // through its exact model and the inverse depth on the grid, ray-traced.
        let scene = generate(kind, SEED, frame, &params)?;
        let (mut images, inv_depth) = render_scene(&scene, &[], &source.rig, spp, &grid)?;
        if params.difficulty.is_hard() {
            // Per-camera gain, gamma, vignetting, blur and noise; the ground truth is unchanged.
            let mut effects = CameraEffects::draw(SEED, frame, source.rig.cameras.len());
            auto_expose(&mut effects, &images);
            apply_all(&effects, &source.rig.cameras, &mut images)?;
        }
        let elapsed = t0.elapsed();
        let views: Vec<(&[u8], usize, usize)> = images
            .iter()
            .zip(&source.rig.cameras)
            .map(|(img, c)| {
                (
                    img.as_slice(),
                    c.model.width() as usize,
                    c.model.height() as usize,
                )
            })
            .collect();
        let sheet = contact_sheet(
            &views,
            4,
            &inv_depth,
            GT_WIDTH,
            GT_HEIGHT,
            1.0 / source.min_depth_m,
        );
        let suffix = if params.difficulty.is_hard() {
            "_hard"
        } else {
            ""
        };
        let path = out.join(format!("synth_{}{suffix}.png", kind.name()));
        omnimvs_data::image_io::write_png_u8(&path, sheet.width, sheet.height, 3, &sheet.data)?;
        println!(
            "{}: frame {frame}, {} objects, {}, {spp} spp, rendered in {:.2} s -> {}",
            kind.name(),
            scene.objects.len(),
            if scene.sky.is_some() { "sky" } else { "room" },
            elapsed.as_secs_f64(),
            path.display()
        );
    }
    Ok(())
}
