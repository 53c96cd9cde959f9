//! Renders one `things` and one `house` frame with the published rig and
//! saves their contact sheets (4 fisheyes + ground truth in colour), e.g.
//!
//! ```text
//! cargo run --release -p omnimvs-synth --example contact_sheet -- docs/images 2 3 1
//! ```
//! (output folder, `things` frame, `house` frame, samples per pixel, and
//! optionally `hard`, which writes `synth_things_hard.png` and
//! `synth_house_hard.png` with the camera effects; seed 0).

use std::path::PathBuf;
use std::time::Instant;

use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::camera_effects::{CameraEffects, apply_all, auto_expose};
use omnimvs_synth::contact::contact_sheet;
use omnimvs_synth::dataset::{GT_HEIGHT, GT_PHI_DEG, GT_WIDTH, render_scene};
use omnimvs_synth::rig::{preset_rig, rig_radius_m};
use omnimvs_synth::{Difficulty, GenParams, SceneKind, generate};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = PathBuf::from(args.first().map_or("docs/images", String::as_str));
    let things_frame: u32 = args.get(1).map_or(Ok(2), |s| s.parse())?;
    let house_frame: u32 = args.get(2).map_or(Ok(3), |s| s.parse())?;
    let spp: u32 = args.get(3).map_or(Ok(1), |s| s.parse())?;
    std::fs::create_dir_all(&out)?;
    let source = preset_rig()?;
    let mut params = GenParams::new(source.min_depth_m, rig_radius_m(&source.rig));
    params.difficulty = args
        .get(4)
        .map_or(Ok(Difficulty::Standard), |s| s.parse())?;
    let grid = EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG)?;
    for (kind, frame) in [
        (SceneKind::Things, things_frame),
        (SceneKind::House, house_frame),
    ] {
        let t0 = Instant::now();
        let scene = generate(kind, 0, frame, &params)?;
        let (mut images, inv_depth) = render_scene(&scene, &[], &source.rig, spp, &grid)?;
        if params.difficulty.is_hard() {
            let mut effects = CameraEffects::draw(0, frame, source.rig.cameras.len());
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
