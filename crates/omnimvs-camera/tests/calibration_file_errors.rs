#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! Bad Basalt and Kalibr calibration files, and rigs their writers cannot state: each error
//! names the file and the field.

use std::path::Path;

use omnimvs_camera::{
    Camera, CameraModel, CentralCamera, KannalaBrandt4, Lens, OcamModel, Pose, Rig, RigFormat,
    basalt_calibration_json, kalibr_camchain_yaml, parse_basalt_calibration, parse_kalibr_camchain,
};

#[allow(dead_code)]
#[path = "support/calib_rigs.rs"]
mod calib_rigs;

#[path = "support/sunny_cam1.rs"]
mod sunny;

const BASALT_PATH: &str = "/calib/tumvi/calibration.json";
const KALIBR_PATH: &str = "/calib/rig-camchain.yaml";

/// A valid Basalt file of two cameras; tests replace parts of it.
const BASALT: &str = r#"{"value0": {
  "T_imu_cam": [
    {"px": 0.1, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0},
    {"px": -0.1, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": 0.7071067811865476, "qz": 0.0, "qw": 0.7071067811865476}
  ],
  "intrinsics": [
    {"camera_type": "ds", "intrinsics": {"fx": 158.3, "fy": 158.2, "cx": 254.9, "cy": 256.8, "xi": -0.17, "alpha": 0.59}},
    {"camera_type": "kb4", "intrinsics": {"fx": 190.9, "fy": 190.9, "cx": 254.9, "cy": 256.8, "k1": 0.003, "k2": 0.0007, "k3": -0.002, "k4": 0.0002}}
  ],
  "resolution": [[512, 512], [512, 512]]
}}"#;

/// A valid Kalibr chain of two cameras; tests replace parts of it.
const KALIBR: &str = "cam0:
  camera_model: pinhole
  intrinsics: [458.654, 457.296, 367.215, 248.375]
  distortion_model: radtan
  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
  resolution: [752, 480]
cam1:
  T_cn_cnm1:
  - [1.0, 0.0, 0.0, -0.11]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: ds
  intrinsics: [-0.17, 0.59, 158.3, 158.2, 254.9, 256.8]
  distortion_model: none
  distortion_coeffs: []
  resolution: [512, 512]
";

fn basalt_err(text: &str) -> String {
    parse_basalt_calibration(Path::new(BASALT_PATH), text)
        .unwrap_err()
        .to_string()
}

fn kalibr_err(text: &str) -> String {
    parse_kalibr_camchain(Path::new(KALIBR_PATH), text)
        .unwrap_err()
        .to_string()
}

/// Asserts the message names the file and each of `parts`.
fn assert_names(e: &str, file: &str, parts: &[&str]) {
    assert!(e.contains(file), "{e}");
    for part in parts {
        assert!(e.contains(part), "{part:?} not in {e}");
    }
}

#[test]
fn the_valid_files_parse() {
    assert_eq!(
        parse_basalt_calibration(Path::new(BASALT_PATH), BASALT)
            .unwrap()
            .len(),
        2
    );
    assert_eq!(
        parse_kalibr_camchain(Path::new(KALIBR_PATH), KALIBR)
            .unwrap()
            .len(),
        2
    );
}

#[test]
fn basalt_unknown_camera_type_lists_the_supported() {
    let e = basalt_err(&BASALT.replace(r#""kb4""#, r#""pinhole-radtan8""#));
    assert_names(
        &e,
        BASALT_PATH,
        &[
            "value0.intrinsics[1].camera_type",
            "pinhole-radtan8",
            "\"ds\"",
            "\"ucm\"",
        ],
    );
    // Checked before the parameters: Basalt's `bal` has no cx.
    let e = basalt_err(&BASALT.replace(
        r#""kb4", "intrinsics": {"fx": 190.9, "fy": 190.9, "cx": 254.9,"#,
        r#""bal", "intrinsics": {"fx": 190.9, "fy": 190.9,"#,
    ));
    assert_names(
        &e,
        BASALT_PATH,
        &[
            "value0.intrinsics[1].camera_type",
            "\"bal\"",
            "expected \"ds\"",
        ],
    );
}

#[test]
fn basalt_missing_parameter_is_named() {
    let e = basalt_err(&BASALT.replace(r#""xi": -0.17, "#, ""));
    assert_names(
        &e,
        BASALT_PATH,
        &["value0.intrinsics[0].intrinsics.xi", "missing"],
    );
}

#[test]
fn basalt_zero_quaternion_is_refused_and_a_long_one_normalised() {
    let zero = BASALT.replace(
        r#""qy": 0.7071067811865476, "qz": 0.0, "qw": 0.7071067811865476"#,
        r#""qy": 0.0, "qz": 0.0, "qw": 0.0"#,
    );
    assert_names(
        &basalt_err(&zero),
        BASALT_PATH,
        &["value0.T_imu_cam[1]", "quaternion"],
    );
    let long = BASALT.replace("0.7071067811865476", "2.0");
    let rig = parse_basalt_calibration(Path::new(BASALT_PATH), &long).unwrap();
    let angle = rig.cameras[1].pose.rvec[1];
    assert!(
        (angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12,
        "{angle}"
    );
}

#[test]
fn basalt_list_lengths_must_agree() {
    let e = basalt_err(&BASALT.replace("[[512, 512], [512, 512]]", "[[512, 512]]"));
    assert_names(
        &e,
        BASALT_PATH,
        &["value0.resolution", "one entry per camera", "found 1"],
    );
    let e = basalt_err(&BASALT.replace("[[512, 512], [512, 512]]", "[[512, 512], [0, 512]]"));
    assert_names(&e, BASALT_PATH, &["value0.resolution[1]", "positive"]);
}

#[test]
fn basalt_parameters_the_model_refuses_name_the_camera() {
    let e = basalt_err(&BASALT.replace(r#""alpha": 0.59"#, r#""alpha": 1.5"#));
    assert_names(&e, BASALT_PATH, &["value0.intrinsics[0]", "alpha"]);
    let e = basalt_err(&BASALT.replace(r#""fx": 190.9"#, r#""fx": "wide""#));
    assert_names(&e, BASALT_PATH, &["value0.intrinsics[1].intrinsics"]);
    let e = basalt_err("{\"value0\": {\"T_imu_cam\": [}");
    assert_names(&e, BASALT_PATH, &["JSON"]);
}

#[test]
fn kalibr_unknown_models_list_the_supported() {
    let e = kalibr_err(&KALIBR.replace("camera_model: ds", "camera_model: fov"));
    assert_names(
        &e,
        KALIBR_PATH,
        &["cam1.camera_model", "\"fov\"", "omni + radtan"],
    );
    let e = kalibr_err(&KALIBR.replace("distortion_model: radtan", "distortion_model: fov"));
    assert_names(
        &e,
        KALIBR_PATH,
        &["cam0.distortion_model", "\"fov\"", "pinhole + radtan"],
    );
}

#[test]
fn kalibr_wrong_counts_are_named() {
    let e = kalibr_err(&KALIBR.replace(
        "[458.654, 457.296, 367.215, 248.375]",
        "[458.654, 457.296, 367.215]",
    ));
    assert_names(&e, KALIBR_PATH, &["cam0.intrinsics", "[fx, fy, cx, cy]"]);
    let e = kalibr_err(&KALIBR.replace("distortion_coeffs: []", "distortion_coeffs: [0.1]"));
    assert_names(&e, KALIBR_PATH, &["cam1.distortion_coeffs"]);
    let e = kalibr_err(&KALIBR.replace("  resolution: [752, 480]\n", ""));
    assert_names(&e, KALIBR_PATH, &["cam0", "resolution"]);
}

#[test]
fn kalibr_missing_or_malformed_transform_is_named() {
    let start = KALIBR.find("  T_cn_cnm1").unwrap();
    let end = KALIBR.find("  camera_model: ds").unwrap();
    let missing = format!("{}{}", &KALIBR[..start], &KALIBR[end..]);
    assert_names(
        &kalibr_err(&missing),
        KALIBR_PATH,
        &["cam1.T_cn_cnm1", "missing"],
    );
    let three = KALIBR.replace("  - [0.0, 0.0, 0.0, 1.0]\n", "");
    assert_names(&kalibr_err(&three), KALIBR_PATH, &["cam1.T_cn_cnm1", "4x4"]);
    let short_row = KALIBR.replace("[0.0, 1.0, 0.0, 0.0]", "[0.0, 1.0, 0.0]");
    assert_names(
        &kalibr_err(&short_row),
        KALIBR_PATH,
        &["cam1.T_cn_cnm1", "4x4"],
    );
    let sheared = KALIBR.replace("[0.0, 1.0, 0.0, 0.0]", "[0.01, 1.0, 0.0, 0.0]");
    assert_names(
        &kalibr_err(&sheared),
        KALIBR_PATH,
        &["cam1.T_cn_cnm1", "rotation"],
    );
    let projective = KALIBR.replace("[0.0, 0.0, 0.0, 1.0]", "[0.0, 0.0, 0.5, 1.0]");
    assert_names(
        &kalibr_err(&projective),
        KALIBR_PATH,
        &["cam1.T_cn_cnm1", "last row"],
    );
}

#[test]
fn kalibr_camera_keys_must_be_consecutive() {
    let gap = KALIBR.replace("cam1:", "cam2:");
    assert_names(&kalibr_err(&gap), KALIBR_PATH, &["cam1", "missing", "cam2"]);
    let stray = format!("{KALIBR}imu0:\n  rostopic: /imu0\n");
    assert_names(&kalibr_err(&stray), KALIBR_PATH, &["imu0", "cam0, cam1"]);
    let e = kalibr_err(&KALIBR.replace("intrinsics: [-0.17, 0.59,", "intrinsics: [-0.17, 1.59,"));
    assert_names(&e, KALIBR_PATH, &["cam1.intrinsics", "alpha"]);
}

#[test]
fn writers_refuse_models_their_format_lacks() {
    let ocam = Camera::new(
        1,
        "cam1",
        CameraModel::Ocam(sunny::sunny_cam1()),
        Pose {
            rvec: [0.0; 3],
            t_m: [0.0; 3],
        },
        None,
    );
    let mut rig = calib_rigs::basalt_rig();
    rig.cameras.push(ocam);
    let e = basalt_calibration_json(&rig).unwrap_err().to_string();
    assert_names(
        &e,
        "calibration.json",
        &[
            "cameras[5].model",
            "Basalt's calibration.json has no ocam camera",
        ],
    );
    let e = kalibr_camchain_yaml(&rig).unwrap_err().to_string();
    assert_names(&e, "camchain.yaml", &["cameras[5].model", "no ocam camera"]);

    // Distortion Basalt has no model for.
    for (lens, name) in [
        (calib_rigs::pinhole_radtan(), "pinhole"),
        (calib_rigs::ucm_radtan(), "unified"),
    ] {
        let rig = Rig::new(vec![calib_rigs::camera(
            0, lens, 640, 480, [0.0; 3], [0.0; 3],
        )]);
        let e = basalt_calibration_json(&rig).unwrap_err().to_string();
        assert_names(
            &e,
            "calibration.json",
            &["cameras[0].model", name, "distortion"],
        );
    }

    // A narrower field of view than the model's, and a Kannala-Brandt bound set apart.
    let narrowed = CentralCamera::new(calib_rigs::ds(), 512, 512, Some(150.0)).unwrap();
    let Lens::KannalaBrandt4(kb) = calib_rigs::kb4() else {
        unreachable!()
    };
    let bound = KannalaBrandt4::with_max_fov_deg(kb, 200.0).unwrap();
    let bound = CentralCamera::new(Lens::KannalaBrandt4(bound), 848, 800, None).unwrap();
    for central in [narrowed, bound] {
        let pose = Pose {
            rvec: [0.0; 3],
            t_m: [0.0; 3],
        };
        let rig = Rig::new(vec![Camera::new(
            0,
            "cam0",
            CameraModel::Central(central),
            pose,
            None,
        )]);
        let e = kalibr_camchain_yaml(&rig).unwrap_err().to_string();
        assert_names(&e, "camchain.yaml", &["cameras[0].model", "field of view"]);
        let e = basalt_calibration_json(&rig).unwrap_err().to_string();
        assert_names(
            &e,
            "calibration.json",
            &["cameras[0].model", "field of view"],
        );
    }
}

#[test]
fn detection_names_what_it_expected() {
    let dir = tempfile::tempdir().unwrap();
    let yaml = dir.path().join("rig.yaml");
    std::fs::write(&yaml, "imu0:\n  rostopic: /imu0\n").unwrap();
    let e = RigFormat::detect(&yaml).unwrap_err().to_string();
    assert_names(&e, "rig.yaml", &["cameras", "cam0"]);
    let e = RigFormat::detect(dir.path()).unwrap_err().to_string();
    assert_names(
        &e,
        &dir.path().display().to_string(),
        &["config.yaml", "calibration.json", "camchain"],
    );
    let e = RigFormat::detect(&dir.path().join("absent.json"))
        .unwrap_err()
        .to_string();
    assert_names(&e, "absent.json", &[]);
}
