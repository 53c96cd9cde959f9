//! `omnimvs info`: what a dataset holds.

use std::path::PathBuf;

use anyhow::Result;
use omnimvs_camera::Pixel;
use omnimvs_data::Dataset;

/// Show a dataset's rig, frames and ground truth.
///
/// Prints each camera (image size, FOV, position, optical axis), the baselines
/// between cameras, the frames found and whether ground truth exists.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder (or its config.yaml).
    pub dataset: PathBuf,
}

pub fn run(args: &Args) -> Result<()> {
    let ds = Dataset::open(&args.dataset)?;
    let cfg = &ds.config;
    outln!("dataset      {}", ds.root.display());
    outln!("config       {}", ds.config_path.display());
    outln!(
        "min depth    {} m (largest inverse depth {:.3} 1/m)",
        cfg.min_depth_m,
        1.0 / cfg.min_depth_m
    );
    outln!("images       {}", cfg.img_fmt);
    outln!("cameras      {}", ds.rig.len());
    for (i, cam) in ds.rig.cameras.iter().enumerate() {
        let m = &cam.model;
        let c = cam.center_in_rig();
        let center_px = Pixel::new(f64::from(m.width()) / 2.0, f64::from(m.height()) / 2.0);
        let axis = cam.ray_in_rig(center_px).unwrap_or_default();
        outln!(
            "  cam{} (id {}, {}): {}x{} px, FOV {} deg, centre ({:+.3}, {:+.3}, {:+.3}) m, axis ({:+.2}, {:+.2}, {:+.2}), dir {}",
            i + 1,
            cam.id,
            m.name(),
            m.width(),
            m.height(),
            m.max_fov_deg(),
            c.x,
            c.y,
            c.z,
            axis.x,
            axis.y,
            axis.z,
            cam.img_dir
        );
    }
    outln!("baselines");
    for (i, j, b) in ds.rig.baselines_m() {
        outln!("  cam{}-cam{}: {b:.3} m", i + 1, j + 1);
    }
    let range = cfg.frames.indices();
    let found = ds.frames_found();
    outln!(
        "frames       {}..{} step {}: {} listed, {} found{}",
        cfg.frames.start,
        cfg.frames.end,
        cfg.frames.step,
        range.len(),
        found.len(),
        if found.is_empty() {
            String::new()
        } else {
            format!(" ({:?} .. {:?})", found[0], found[found.len() - 1])
        }
    );
    let with_gt: Vec<u32> = found
        .iter()
        .copied()
        .filter(|&f| ds.gt_path(f).is_some())
        .collect();
    match with_gt.first() {
        Some(&f) => outln!(
            "ground truth {} of {} frames (e.g. {})",
            with_gt.len(),
            found.len(),
            ds.gt_path(f)
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        ),
        None => outln!("ground truth none"),
    }
    Ok(())
}
