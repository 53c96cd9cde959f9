//! Copies a generated dataset with its images rendered again through ideal
//! cameras (the scenes of `scene/*.json` without their `camera_effects`):
//! the same scenes and ground truth, to measure what the camera effects of
//! a `hard` dataset cost a method, e.g.
//!
//! ```text
//! cargo run --release -p omnimvs-synth --example ideal_cameras -- DATASET OUT 1 8
//! ```
//! (dataset folder made by `omnimvs synth`, output folder, first and last
//! frame). Samples per pixel from its `synth.json`; no user meshes.

use std::path::PathBuf;

use omnimvs_data::Dataset;
use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::dataset::{GT_HEIGHT, GT_PHI_DEG, GT_WIDTH, render_scene};
use omnimvs_synth::{SceneSpec, SynthSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(src), Some(out)) = (args.first(), args.get(1)) else {
        return Err("usage: ideal_cameras DATASET OUT [FIRST LAST]".into());
    };
    let (src, out) = (PathBuf::from(src), PathBuf::from(out));
    let first: u32 = args.get(2).map_or(Ok(1), |s| s.parse())?;
    let last: u32 = args.get(3).map_or(Ok(first), |s| s.parse())?;
    let settings: SynthSettings =
        serde_json::from_str(&std::fs::read_to_string(src.join("synth.json"))?)?;
    let rig = Dataset::open(&src)?.rig;
    let grid = EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG)?;
    std::fs::create_dir_all(&out)?;
    for name in ["config.yaml", "synth.json"] {
        omnimvs_camera::fs::write_atomic(&out.join(name), &std::fs::read(src.join(name))?)?;
    }
    for frame in first..=last {
        let mut scene: SceneSpec = serde_json::from_str(&std::fs::read_to_string(
            src.join(format!("scene/{frame:05}.json")),
        )?)?;
        scene.camera_effects.clear();
        let (images, _) = render_scene(&scene, &[], &rig, settings.spp, &grid)?;
        for (cam, img) in rig.cameras.iter().zip(&images) {
            let dir = out.join(&cam.img_dir);
            std::fs::create_dir_all(&dir)?;
            let (w, h) = (cam.model.width() as usize, cam.model.height() as usize);
            omnimvs_data::image_io::write_png_u8(
                &dir.join(format!("{frame:05}.png")),
                w,
                h,
                1,
                img,
            )?;
        }
        for sub in ["omnidepth_gt_640", "scene"] {
            let ext = if sub == "scene" { "json" } else { "tiff" };
            std::fs::create_dir_all(out.join(sub))?;
            let name = format!("{sub}/{frame:05}.{ext}");
            omnimvs_camera::fs::write_atomic(&out.join(&name), &std::fs::read(src.join(&name))?)?;
        }
        println!("frame {frame}: ideal images written");
    }
    Ok(())
}
