//! `omnimvs info`: what a dataset holds.

use std::path::PathBuf;

use anyhow::Result;
use omnimvs_data::Dataset;

/// Show a dataset's rig, frames and ground truth.
///
/// Prints the rig file and its format, the frame the rig is expressed in (`--rig-frame`), each
/// camera (model, image size, FOV, position, optical axis), the baselines between cameras in
/// metres, how the images and masks were found, the frames found and whether ground truth
/// exists.
/// For a released-layout folder it says in which unit poses.txt was read
/// (`--pose-unit`), and flags baselines no camera rig has (a wrong unit).
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder (or its config.yaml).
    pub dataset: PathBuf,
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    let ds = datasets.open(&args.dataset)?;
    let cfg = &ds.config;
    outln!("dataset      {}", ds.root.display());
    outln!("rig file     {}", ds.found.rig);
    outln!("frame        {}", ds.frame.describe());
    if let Some(note) = off_centre_note(&ds) {
        outln!("  note: {note}");
    }
    if Dataset::is_released_layout(&args.dataset) {
        let unit = datasets.pose_unit().unwrap_or_default();
        outln!(
            "poses        poses.txt, translations read in {unit} (--pose-unit), shown in metres"
        );
    }
    outln!(
        "min depth    {} m (largest inverse depth {:.3} 1/m)",
        cfg.min_depth_m,
        1.0 / cfg.min_depth_m
    );
    outln!("images       {}", ds.found.images);
    outln!("masks");
    for (i, m) in ds.found.masks.iter().enumerate() {
        outln!("  camera {}: {m}", i + 1);
    }
    crate::cmd::rig::print_rig(&ds.rig);
    let baselines = ds.rig.baselines_m();
    if let Some(note) = implausible_baselines(baselines.iter().map(|&(_, _, b)| b)) {
        outln!("  note: {note}");
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

/// Says when the calibration frame is far from the frame fitted to the cameras (its origin
/// away from their centre by more than a quarter of their spread, or tilted by more than 5
/// degrees), where `--rig-frame fitted` gives a centred, level panorama; `None` otherwise.
fn off_centre_note(ds: &Dataset) -> Option<String> {
    if ds.frame.choice != "calibration" {
        return None;
    }
    let fitted_from_rig = ds.rig.fitted_frame().ok()?;
    // The cameras' mean position: the fitted frame's origin, in the calibration frame.
    let centre = fitted_from_rig.inverse().translation.vector;
    let offset_m = centre.norm();
    let tilt_deg = fitted_from_rig.rotation.angle().to_degrees();
    let spread_m = ds
        .rig
        .cameras
        .iter()
        .map(|c| (c.center_in_rig() - centre).coords.norm())
        .fold(0.0, f64::max);
    (offset_m > 0.25 * spread_m || tilt_deg > 5.0).then(|| {
        format!(
            "the cameras' centre is {offset_m:.3} m from this frame's origin and their plane is tilted {tilt_deg:.1} degrees from its x-z plane: --rig-frame fitted centres and levels the panorama"
        )
    })
}

/// Baselines of a multi-camera rig lie between a centimetre and a few metres; outside that the
/// poses were most likely read in the wrong unit. Says so, or `None`.
fn implausible_baselines(baselines: impl Iterator<Item = f64>) -> Option<String> {
    let (lo, hi) = baselines.fold((f64::INFINITY, 0f64), |(lo, hi), b| (lo.min(b), hi.max(b)));
    if !hi.is_finite() || hi == 0.0 {
        return None;
    }
    (hi > 5.0 || lo < 0.01).then(|| {
        format!(
            "baselines from {lo:.3} m to {hi:.3} m are unlike a camera rig's: are the poses in another unit? (--pose-unit m|cm|mm for a released-layout folder)"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::implausible_baselines;

    #[test]
    fn a_rig_in_the_wrong_unit_is_flagged() {
        // The published rig: 0.6 m from the centre, 0.85 to 1.2 m apart.
        assert_eq!(implausible_baselines([0.85, 1.2].into_iter()), None);
        // Its poses in mm read as cm, and in cm read as mm.
        assert!(implausible_baselines([8.5, 12.0].into_iter()).is_some());
        assert!(implausible_baselines([0.0085, 0.012].into_iter()).is_some());
    }
}
