#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! The camera model and the readers on the two real samples of the reference
//! implementation (`../shared/data/omnimvs-samples`).

use std::path::Path;

use omnimvs_camera::nalgebra::Vector3;
use omnimvs_camera::{CameraModel, Pixel, Rig, ValidityMask, read_config_rig, read_ocam_txt_rig};

#[path = "support/samples.rs"]
mod samples;
use samples::samples;

fn rig(name: &str) -> Rig {
    read_config_rig(&samples().join(name).join("config.yaml")).unwrap()
}

/// Worst (pixel error of pixel->ray->pixel, angle error in radians of
/// ray->pixel->ray) over a grid of directions inside the FOV.
fn round_trip_errors(model: &CameraModel) -> (f64, f64) {
    let (mut worst_px, mut worst_ang) = (0f64, 0f64);
    let half_fov = model.max_fov_deg().to_radians() / 2.0;
    let steps = 60;
    for i in 0..=steps {
        // Angle from the optical axis, up to just inside the FOV edge.
        let alpha = half_fov * 0.999 * f64::from(i) / f64::from(steps);
        for j in 0..36 {
            let az = f64::from(j) * 10f64.to_radians();
            let ray = Vector3::new(alpha.sin() * az.cos(), alpha.sin() * az.sin(), alpha.cos());
            let px = model.project(&(ray * 3.7)).expect("inside the FOV");
            let Some(back) = model.unproject(px) else {
                // The forward and the fitted inverse polynomial disagree by a
                // hair at the very edge of the FOV; only there is this allowed.
                assert!(
                    alpha > 0.99 * half_fov,
                    "unproject failed at {} deg",
                    alpha.to_degrees()
                );
                continue;
            };
            worst_ang = worst_ang.max(back.angle(&ray));
            let px2 = model.project(&back).unwrap();
            worst_px =
                worst_px.max(((px2.col - px.col).powi(2) + (px2.row - px.row).powi(2)).sqrt());
        }
    }
    (worst_px, worst_ang)
}

#[test]
fn round_trip_is_tight_on_both_samples() {
    // The round trip is limited by how well each file's fitted inverse
    // polynomial agrees with its forward one. Measured worst cases: sunny
    // 0.0056 px / 0.0017 deg; itbt 3.57 px / 0.56 deg (its inv_poly is given
    // to 6 digits and disagrees with poly by up to ~3.5 px of radius, which
    // scripts/ocam_roundtrip.py confirms independently). Bounds sit just above.
    for (name, max_px, max_ang_deg) in [("sunny_single", 0.01, 0.003), ("itbt_sample", 3.8, 0.6)] {
        for (i, cam) in rig(name).cameras.iter().enumerate() {
            let (px, ang) = round_trip_errors(&cam.model);
            println!(
                "{name} cam{}: pixel {px:.5} px, angle {:.5} deg",
                i + 1,
                ang.to_degrees()
            );
            assert!(px < max_px, "{name} cam{}: pixel round trip {px}", i + 1);
            assert!(
                ang.to_degrees() < max_ang_deg,
                "{name} cam{}: angle {}",
                i + 1,
                ang.to_degrees()
            );
        }
    }
}

#[test]
fn sunny_rig_is_the_published_one() {
    let r = rig("sunny_single");
    assert_eq!(r.len(), 4);
    for (_, _, b) in r.baselines_m().iter().filter(|(i, j, _)| (j - i) % 2 == 1) {
        // Neighbours 90 degrees apart at 0.6 m: 0.6 * sqrt(2).
        assert!((b - 0.6 * 2f64.sqrt()).abs() < 1e-9);
    }
    // Camera 2 (ry = pi/2, t = (0.6, 0, 0)) looks along rig +x.
    let c2 = &r.cameras[1];
    let axis = c2.ray_in_rig(Pixel::new(399.0, 383.0)).unwrap();
    assert!((axis - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-9);
    assert_eq!(c2.img_dir, "cam2");
    assert_eq!(c2.invalid_mask.as_deref(), Some("mask2.png"));
}

#[test]
fn itbt_counts_written_as_floats_are_accepted() {
    let r = rig("itbt_sample");
    let CameraModel::Ocam(m) = &r.cameras[0].model else {
        panic!("the sample is an OCamCalib rig")
    };
    assert_eq!(m.inv_poly.len(), 13);
    assert_eq!((m.width, m.height), (1600, 1532));
    assert!((m.d + 2.91382e-4).abs() < 1e-12);
}

#[test]
fn fov_mask_without_mask_file_and_nothing_written() {
    let dir = samples().join("sunny_single");
    let before: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    let r = rig("sunny_single");
    let mask = ValidityMask::for_camera(&r.cameras[0], &dir).unwrap();
    // The 220-degree circle: the centre is valid, the corners are not.
    assert!(mask.is_valid(399, 383));
    assert!(!mask.is_valid(0, 0));
    let frac = mask.count_valid() as f64 / (800.0 * 768.0);
    assert!(frac > 0.6 && frac < 0.95, "valid fraction {frac}");
    let after: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(before, after);
}

/// Writes the rig as released-dataset files (`ocamK.txt`, `poses.txt` in cm).
#[test]
fn ocam_txt_files_give_the_same_rig() {
    for name in ["sunny_single", "itbt_sample"] {
        let from_yaml = rig(name);
        let dir = tempfile::tempdir().unwrap();
        omnimvs_camera::write_ocam_txt_rig(&from_yaml, dir.path()).unwrap();
        let from_txt = read_ocam_txt_rig(dir.path(), 220.0).unwrap();
        assert_eq!(from_txt.len(), from_yaml.len());
        for (a, b) in from_txt.cameras.iter().zip(&from_yaml.cameras) {
            assert_eq!(a.model, b.model, "{name}: intrinsics");
            // cm -> m conversion may differ in the last bit.
            let (pa, pb) = (a.pose.to_array(), b.pose.to_array());
            for k in 0..6 {
                assert!(
                    (pa[k] - pb[k]).abs() < 1e-12,
                    "{name}: pose {pa:?} vs {pb:?}"
                );
            }
        }
    }
}

#[test]
fn written_cameras_section_reads_back_the_same_rig() {
    for name in ["sunny_single", "itbt_sample"] {
        let rig = rig(name);
        let text = omnimvs_camera::config_cameras_yaml(&rig).unwrap();
        assert!(text.starts_with("cameras:\n  - cam_id: 1\n"), "{text}");
        let back = omnimvs_camera::parse_config_rig(Path::new("written.yaml"), &text).unwrap();
        assert_eq!(back, rig, "{name}");
    }
}

#[test]
fn a_resized_camera_sees_the_same_rays() {
    let model = &rig("sunny_single").cameras[0].model;
    let half = model.resized(model.height() / 2, model.width() / 2);
    assert_eq!((half.width(), half.height()), (400, 384));
    assert_eq!(model.resized(model.height(), model.width()), *model);
    for p in [
        Vector3::new(0.3, -0.2, 1.0),
        Vector3::new(-1.0, 0.5, 0.2),
        Vector3::new(0.7, 0.7, -0.3),
    ] {
        let (a, b) = (model.project(&p).unwrap(), half.project(&p).unwrap());
        assert!((b.col - ((a.col + 0.5) / 2.0 - 0.5)).abs() < 1e-9, "{p:?}");
        assert!((b.row - ((a.row + 0.5) / 2.0 - 0.5)).abs() < 1e-9, "{p:?}");
    }
}
