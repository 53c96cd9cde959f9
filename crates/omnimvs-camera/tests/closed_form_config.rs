#![allow(clippy::unwrap_used, clippy::expect_used)]
//! `config.yaml` with the closed-form camera models: read, written back exactly, refused
//! with the field named; their cameras resized and tabulated as their projection is.

use std::path::Path;

use nalgebra::Vector3;
use omnimvs_camera::{CameraError, CameraModel, ConfigFile, config_cameras_yaml, parse_config_rig};

/// One camera of each closed-form model (parameters of the kind Basalt and Kalibr write).
const CONFIG: &str = r#"
cameras:
  - cam_id: 1
    model: ds
    intrinsics: [380.0, 381.5, 511.5, 510.0, -0.2, 0.59]
    image_size: [1024, 1024]
    pose: [0.0, 0.0, 0.0, 0.1, 0.0, 0.0]
  - cam_id: 2
    model: eucm
    intrinsics: [460.0, 459.0, 365.0, 249.0, 0.6, 1.1]
    image_size: [480, 752]
    pose: [0.0, 1.5707963, 0.0, 0.0, 0.0, 0.1]
    max_fov: 200.0
  - cam_id: 3
    model: ucm
    intrinsics: [760.0, 758.0, 640.0, 480.0, 1.2]
    distortion: [-0.2, 0.05, 0.0003, -0.0002]
    image_size: [960, 1280]
    pose: [0.0, 3.1415926, 0.0, -0.1, 0.0, 0.0]
    max_fov: 180.0
  - cam_id: 4
    model: kb4
    intrinsics: [285.0, 286.0, 424.0, 400.0]
    distortion: [-0.006, 0.04, -0.037, 0.006]
    image_size: [800, 848]
    pose: [0.0, -1.5707963, 0.0, 0.0, 0.0, -0.1]
    max_fov: 240.0
  - cam_id: 5
    model: pinhole-radtan
    intrinsics: [458.6, 457.3, 367.2, 248.4]
    distortion: [-0.28, 0.07, 0.0002, 0.00002]
    image_size: [480, 752]
    pose: [0.0, 0.0, 0.0, 0.0, 0.2, 0.0]
"#;

#[test]
fn closed_form_rigs_read_and_write_back_exactly() {
    let path = Path::new("config.yaml");
    let rig = parse_config_rig(path, CONFIG).unwrap();
    let names: Vec<&str> = rig.cameras.iter().map(|c| c.model.name()).collect();
    assert_eq!(names, ["ds", "eucm", "ucm", "kb4", "pinhole-radtan"]);
    assert_eq!(rig.cameras[3].model.max_fov_deg(), 240.0);
    assert_eq!(
        (rig.cameras[1].model.width(), rig.cameras[1].model.height()),
        (752, 480)
    );
    let text = config_cameras_yaml(&rig).unwrap();
    assert_eq!(parse_config_rig(path, &text).unwrap(), rig, "{text}");
    // The content key (the lookup-table cache's) tells the models apart.
    let mut other = rig.clone();
    other.cameras.swap(0, 1);
    assert_ne!(rig.content_key(), other.content_key());
}

#[test]
fn every_camera_round_trips_and_its_field_of_view_is_enforced() {
    let rig = parse_config_rig(Path::new("config.yaml"), CONFIG).unwrap();
    for cam in &rig.cameras {
        let model = &cam.model;
        let half = model.half_fov_rad();
        for k in 0..=20 {
            let alpha = half * f64::from(k) / 20.0 * 0.999;
            for az in [0.3f64, 1.9, 4.0] {
                let ray = Vector3::new(alpha.sin() * az.cos(), alpha.sin() * az.sin(), alpha.cos());
                // Pixels of the image (a pinhole image is smaller than its model's domain).
                let Some(px) = model.project(&ray).filter(|&px| model.contains(px)) else {
                    continue;
                };
                let back = model
                    .unproject(px)
                    .unwrap_or_else(|| panic!("{} {alpha} {az}: {px:?}", model.name()));
                assert!((back - ray).norm() < 1e-8, "{} {alpha} {az}", model.name());
            }
        }
        let beyond = half + 0.01;
        if beyond < std::f64::consts::PI {
            let ray = Vector3::new(beyond.sin(), 0.0, beyond.cos());
            assert!(model.project(&ray).is_none(), "{}", model.name());
        }
    }
}

#[test]
fn a_resized_closed_form_camera_sees_the_same_rays() {
    let rig = parse_config_rig(Path::new("config.yaml"), CONFIG).unwrap();
    for cam in &rig.cameras {
        let (w, h) = (cam.model.width(), cam.model.height());
        let small = cam.model.resized(h / 2, w / 2);
        let ray = Vector3::new(0.3, -0.2, 0.9).normalize();
        let (a, b) = (
            cam.model.project(&ray).unwrap(),
            small.project(&ray).unwrap(),
        );
        assert!(
            (b.col - ((a.col + 0.5) / 2.0 - 0.5)).abs() < 1e-9,
            "{}",
            cam.model.name()
        );
        assert!(
            (b.row - ((a.row + 0.5) / 2.0 - 0.5)).abs() < 1e-9,
            "{}",
            cam.model.name()
        );
    }
}

#[test]
fn radial_lenses_are_tabulated_and_tangential_ones_are_not() {
    let rig = parse_config_rig(Path::new("config.yaml"), CONFIG).unwrap();
    for cam in &rig.cameras {
        let radial = cam.model.radial_projection();
        let CameraModel::Central(central) = &cam.model else {
            unreachable!()
        };
        assert_eq!(
            radial.is_some(),
            central.lens.is_radial(),
            "{}",
            cam.model.name()
        );
        let Some(radial) = radial else { continue };
        let alpha = 0.8f64;
        let azimuth = 0.7f64;
        let p = Vector3::new(
            alpha.sin() * azimuth.cos(),
            alpha.sin() * azimuth.sin(),
            alpha.cos(),
        );
        let want = cam.model.project(&p).unwrap();
        let r = radial.radius_px(alpha);
        let (u, v) = (r * azimuth.sin(), r * azimuth.cos());
        let row = radial.c * u + radial.d * v + radial.center.row;
        let col = radial.e * u + v + radial.center.col;
        assert!(
            (row - want.row).abs() < 1e-9 && (col - want.col).abs() < 1e-9,
            "{}",
            cam.model.name()
        );
    }
}

#[test]
fn bad_closed_form_entries_name_the_field() {
    let path = Path::new("config.yaml");
    let one = |model: &str, intrinsics: &str, distortion: &str| {
        format!(
            "cameras:\n  - model: {model}\n    intrinsics: [{intrinsics}]\n{distortion}    image_size: [480, 752]\n    pose: [0, 0, 0, 0, 0, 0]\n"
        )
    };
    let err = |text: String| parse_config_rig(path, &text).unwrap_err().to_string();
    let e = err(one("fisheye62", "1, 1, 1, 1", ""));
    assert!(
        e.contains("cameras[0].model") && e.contains("\"kb4\""),
        "{e}"
    );
    let e = err(one("ds", "400, 400, 300, 200, 0.1", ""));
    assert!(
        e.contains("cameras[0].intrinsics") && e.contains("6 (fx, fy, cx, cy, xi, alpha)"),
        "{e}"
    );
    let e = err(one("kb4", "400, 400, 300, 200", ""));
    assert!(e.contains("cameras[0].distortion"), "{e}");
    let e = err(one("eucm", "400, 400, 300, 200, 0.6, -1", ""));
    assert!(e.contains("beta"), "{e}");
    let text = format!(
        "{}    max_fov: 300\n",
        one("pinhole-radtan", "400, 400, 300, 200", "")
    );
    let e = parse_config_rig(path, &text).unwrap_err();
    assert!(
        matches!(e, CameraError::Param { .. }) && e.to_string().contains("max_fov"),
        "{e}"
    );
    // An OCamCalib entry still needs its polynomial.
    let e = err("cameras:\n  - model: ocam\n    image_size: [4, 4]\n    pose: [0, 0, 0, 0, 0, 0]\n    max_fov: 200\n".into());
    assert!(e.contains("cameras[0].poly"), "{e}");
    assert!(ConfigFile::parse(path, CONFIG).is_ok());
}
