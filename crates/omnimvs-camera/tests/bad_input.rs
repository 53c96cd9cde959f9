#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! Bad configuration files give errors naming the file and the field.

use std::path::Path;

use omnimvs_camera::{CameraError, parse_config_rig, read_config_rig, read_ocam_txt_rig};

const GOOD_CAMERA: &str = r#"
cameras:
  - cam_id: 1
    img_dir: cam1
    model: ocam
    poly: [5, -196.656, 0.0, 3.053428e-03, -9.784996e-06, 2.278718e-08]
    inv_poly: [4, 300.9, 181.0, -21.4, 14.9]
    center: [383.0, 399.0]
    affine: [1.0, 0.0, 0.0]
    image_size: [768, 800]
    invalid_mask: mask1.png
    pose: [0, 0, 0, 0, 0, 0.6]
    max_fov: 220.0
"#;

fn err_of(text: &str) -> String {
    parse_config_rig(Path::new("/data/set/config.yaml"), text)
        .unwrap_err()
        .to_string()
}

#[test]
fn good_minimal_config_parses() {
    let rig = parse_config_rig(Path::new("config.yaml"), GOOD_CAMERA).unwrap();
    assert_eq!(rig.len(), 1);
}

#[test]
fn missing_file_names_the_file() {
    let e = read_config_rig(Path::new("/nonexistent/config.yaml")).unwrap_err();
    assert!(matches!(e, CameraError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/config.yaml"));
}

#[test]
fn truncated_file_names_the_missing_field() {
    let cut = &GOOD_CAMERA[..GOOD_CAMERA.find("    image_size").unwrap()];
    let e = err_of(cut);
    assert!(e.contains("config.yaml"), "{e}");
    assert!(e.contains("cameras[0]") && e.contains("image_size"), "{e}");
}

#[test]
fn empty_file_is_an_error() {
    let e = err_of("");
    assert!(e.contains("config.yaml") && e.contains("empty"), "{e}");
}

#[test]
fn malformed_yaml_is_an_error() {
    let e = err_of("cameras: [ { poly: [1, 2 }\n");
    assert!(e.contains("config.yaml") && e.contains("YAML"), "{e}");
}

#[test]
fn poly_count_disagreeing_with_coefficients() {
    let e = err_of(&GOOD_CAMERA.replace("poly: [5, -196.656", "poly: [6, -196.656"));
    assert!(e.contains("cameras[0].poly"), "{e}");
    assert!(e.contains("6") && e.contains("5 follow"), "{e}");
    let e = err_of(&GOOD_CAMERA.replace("inv_poly: [4,", "inv_poly: [3,"));
    assert!(e.contains("cameras[0].inv_poly"), "{e}");
}

#[test]
fn non_numeric_value_names_the_element() {
    let e = err_of(&GOOD_CAMERA.replace("3.053428e-03", "abc"));
    assert!(e.contains("cameras[0].poly[3]"), "{e}");
    let e = err_of(&GOOD_CAMERA.replace("max_fov: 220.0", "max_fov: wide"));
    assert!(e.contains("cameras[0].max_fov"), "{e}");
}

#[test]
fn unknown_model_and_bad_values() {
    let e = err_of(&GOOD_CAMERA.replace("model: ocam", "model: pinhole"));
    assert!(
        e.contains("cameras[0].model") && e.contains("pinhole"),
        "{e}"
    );
    let e = err_of(&GOOD_CAMERA.replace("image_size: [768, 800]", "image_size: [0, 800]"));
    assert!(e.contains("cameras[0].image_size"), "{e}");
    let e = err_of(&GOOD_CAMERA.replace("max_fov: 220.0", "max_fov: -5"));
    assert!(e.contains("cameras[0].max_fov"), "{e}");
    let e = err_of("cameras: []\n");
    assert!(e.contains("cameras") && e.contains("at least one"), "{e}");
}

#[test]
fn ocam_txt_errors_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let e = read_ocam_txt_rig(dir.path(), 220.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("ocam1.txt"), "{e}");
    std::fs::write(
        dir.path().join("ocam1.txt"),
        "# c\n5 -196.6 0 3e-3 -9e-6 2e-8\n3 300 181 x\n383 399\n1 0 0\n768 800\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("poses.txt"), "0 0 0 0 0 60\n").unwrap();
    let e = read_ocam_txt_rig(dir.path(), 220.0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("ocam1.txt") && e.contains("line 3") && e.contains("\"x\""),
        "{e}"
    );
    std::fs::write(
        dir.path().join("ocam1.txt"),
        "5 -196.6 0 3e-3 -9e-6 2e-8\n3 300 181 -21\n383 399\n1 0 0\n768 800\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("poses.txt"), "0 0 0 0 0 60\n0 0 0 0 0 60\n").unwrap();
    let e = read_ocam_txt_rig(dir.path(), 220.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("poses.txt") && e.contains("found 2"), "{e}");
}

#[test]
fn a_model_parameter_out_of_range_names_the_file_and_the_camera() {
    let e = err_of(
        "cameras:\n  - model: ds\n    intrinsics: [100, 100, 50, 50, -0.2, 1.5]\n    image_size: [100, 100]\n    pose: [0, 0, 0, 0, 0, 0]\n",
    );
    assert!(
        e.contains("/data/set/config.yaml")
            && e.contains("cameras[0].intrinsics")
            && e.contains("alpha"),
        "{e}"
    );
}

#[test]
fn a_camera_that_sees_nothing_is_refused() {
    // The principal point 5000 pixels outside a 100x100 image: no pixel in the field of view.
    let e = err_of(
        "cameras:\n  - model: kb4\n    intrinsics: [100, 100, 50, 50]\n    distortion: [0, 0, 0, 0]\n    image_size: [100, 100]\n    pose: [0, 0, 0, 0, 0, 0]\n  - model: kb4\n    intrinsics: [100, 100, 5000, 5000]\n    distortion: [0, 0, 0, 0]\n    image_size: [100, 100]\n    pose: [0, 0, 0, 0, 0, 0]\n",
    );
    assert!(
        e.contains("/data/set/config.yaml") && e.contains("cameras[1]") && e.contains("no pixel"),
        "{e}"
    );
}
