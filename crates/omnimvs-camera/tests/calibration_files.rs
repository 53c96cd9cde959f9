#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! Basalt's `calibration.json` and Kalibr's `camchain.yaml`: published layouts read to the
//! expected rig, every model each states written and read back, formats chained, and the
//! format told from the path.

use std::path::Path;

use nalgebra::{Isometry3, Vector3};
use omnimvs_camera::{
    Camera, CameraModel, Lens, OcamModel, Pose, Rig, RigFormat, basalt_calibration_json,
    config_cameras_yaml, kalibr_camchain_yaml, parse_basalt_calibration, parse_config_rig,
    parse_kalibr_camchain, read_rig_file, write_rig_file,
};

#[allow(dead_code)]
#[path = "support/calib_rigs.rs"]
mod calib_rigs;
use calib_rigs::*;

#[path = "support/sunny_cam1.rs"]
mod sunny;

/// Basalt's TUM-VI double sphere calibration (`data/tumvi_512_ds_calib.json` of the Basalt
/// repository), its vignette shortened; the IMU fields of that version are scalars.
const TUMVI_BASALT: &str = r#"{
    "value0": {
        "T_imu_cam": [
            {"px": 0.04548094812071685, "py": -0.07145370002838907, "pz": -0.046315428444919249,
             "qx": -0.013392900690257393, "qy": -0.6945866755293793, "qz": 0.7192437840259219,
             "qw": 0.007639340823570553},
            {"px": -0.05546984222234079, "py": -0.06999334244486549, "pz": -0.049092582974927929,
             "qx": -0.01340980138125811, "qy": -0.7115668842588793, "qz": 0.7024477338114514,
             "qw": 0.007741299385907546}
        ],
        "intrinsics": [
            {"camera_type": "ds", "intrinsics": {"fx": 158.28600034966977, "fy": 158.2743455478755,
             "cx": 254.96116578191653, "cy": 256.8894394501779, "xi": -0.17213086034353243,
             "alpha": 0.5931177593944744}},
            {"camera_type": "ds", "intrinsics": {"fx": 157.91830144176309, "fy": 157.8901286125632,
             "cx": 252.56547609702953, "cy": 255.02489416194656, "xi": -0.17114780716007858,
             "alpha": 0.5925543396658507}}
        ],
        "resolution": [[512, 512], [512, 512]],
        "calib_accel_bias": [-0.0011791549110128743, -0.007714616665106584, 0.00006733124206236036,
                             0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        "calib_gyro_bias": [-0.00007403817898158015, 0.0000024090695654577384, -0.00001847724206614636,
                            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        "imu_update_rate": 200.0,
        "accel_noise_std": 0.016,
        "gyro_noise_std": 0.000282,
        "accel_bias_std": 0.001,
        "gyro_bias_std": 0.0001,
        "T_mocap_world": {"px": 0.0, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0},
        "T_imu_marker": {"px": 0.0, "py": 0.0, "pz": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0},
        "mocap_time_offset_ns": 0,
        "mocap_to_imu_offset_ns": 0,
        "cam_time_offset_ns": 0,
        "vignette": [
            {"value0": 0, "value1": 10000000000, "value2": [[0.9899372881888493], [1.0], [0.01]]},
            {"value0": 0, "value1": 10000000000, "value2": [[0.9982144512705363], [1.0], [0.01]]}
        ]
    }
}"#;

/// A Kalibr camera chain: two fisheye cameras (`pinhole` + `equidistant`, TUM-VI's values)
/// and one catadioptric-style camera (`omni` + `radtan`, the values of Kalibr's own example),
/// with the optional fields Kalibr writes. `T_cn_cnm1` comes from `rig_from_cam1` =
/// (rvec [0.0044, -0.0007, 0.0008], t [0.1011, 0.0020, -0.0010]) and `rig_from_cam2` =
/// (rvec [0.02, 1.5, -0.03], t [0.05, 0.01, -0.08]).
const CAMCHAIN: &str = "cam0:
  cam_overlaps: [1]
  camera_model: pinhole
  distortion_coeffs: [0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202, 0.00020293673591811182]
  distortion_model: equidistant
  intrinsics: [190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504]
  resolution: [512, 512]
  rostopic: /cam0/image_raw
cam1:
  T_cn_cnm1:
  - [0.9999994350009646, 0.0007984572706323479, 0.0007017576064972502, -0.1011008380355323]
  - [-0.00080153726537325, 0.999990000017075, 0.0043997049744934945, -0.001914544877530421]
  - [-0.0006982376125076478, -0.004400264973537295, 0.999990075016947, 0.001079382427588545]
  - [0.0, 0.0, 0.0, 1.0]
  cam_overlaps: [0]
  camera_model: pinhole
  distortion_coeffs: [0.0034003170790442797, 0.001766278153469831, -0.00266312569781606, 0.0003299517423931039]
  distortion_model: equidistant
  intrinsics: [190.44236969414825, 190.4344384721956, 252.59949716835982, 254.91723064636983]
  resolution: [512, 512]
  rostopic: /cam1/image_raw
cam2:
  T_cn_cnm1:
  - [0.06976412748952876, -0.012001024416585404, -0.9974913242372475, -0.07513986146688739]
  - [0.03312782548496176, 0.9994039821755494, -0.009707089692175347, -0.006761108467532988]
  - [0.9970132966486771, -0.03236751186925773, 0.07012011466855118, 0.05678466897875895]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: omni
  distortion_coeffs: [-0.33518, 0.13211, 0.00055, 0.00057]
  distortion_model: radtan
  intrinsics: [0.80065662, 833.006, 830.345, 373.850, 253.749]
  resolution: [752, 480]
  rostopic: /cam2/image_raw
  timeshift_cam_imu: -8.121e-05
";

#[test]
fn basalt_tumvi_file_reads_to_its_rig() {
    let rig = parse_basalt_calibration(Path::new("calibration.json"), TUMVI_BASALT).unwrap();
    assert_eq!(rig.len(), 2);
    let (name, p) = params_of(lens_of(&rig.cameras[0]));
    assert_eq!(name, "ds");
    let want = [
        158.28600034966977,
        158.2743455478755,
        254.96116578191653,
        256.8894394501779,
    ];
    assert_eq!(
        p,
        [&want[..], &[-0.17213086034353243, 0.5931177593944744]].concat()
    );
    assert_eq!(params_of(lens_of(&rig.cameras[1])).1[5], 0.5925543396658507);
    for (i, cam) in rig.cameras.iter().enumerate() {
        assert_eq!(
            (cam.id, cam.img_dir.as_str()),
            (i as u32, ["cam0", "cam1"][i])
        );
        assert_eq!((cam.model.width(), cam.model.height()), (512, 512));
        assert_eq!(cam.invalid_mask, None);
    }
    // rig_from_cam is T_imu_cam: the translation as written, the quaternion's rotation.
    let cam0 = &rig.cameras[0];
    assert_eq!(
        cam0.pose.t_m,
        [
            0.04548094812071685,
            -0.07145370002838907,
            -0.046315428444919249
        ]
    );
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        0.007639340823570553,
        -0.013392900690257393,
        -0.6945866755293793,
        0.7192437840259219,
    ));
    assert!(cam0.rig_from_cam.rotation.angle_to(&q) < 1e-12);
    // Both cameras look along the IMU's -y axis and sit about 10 cm apart.
    for cam in &rig.cameras {
        assert!((cam.rig_from_cam.rotation * Vector3::z()).y < -0.99);
    }
    assert!(
        (rig.baselines_m()[0].2 - 0.1010).abs() < 1e-3,
        "{:?}",
        rig.baselines_m()
    );
}

#[test]
fn kalibr_camchain_reads_to_its_rig() {
    let rig = parse_kalibr_camchain(Path::new("camchain.yaml"), CAMCHAIN).unwrap();
    assert_eq!(rig.len(), 3);
    let expect = [
        (
            "kb4",
            vec![
                190.97847715128717,
                190.9733070521226,
                254.93170605935475,
                256.8974428996504,
                0.0034823894022493434,
                0.0007150348452162257,
                -0.0020532361418706202,
                0.00020293673591811182,
            ],
        ),
        (
            "kb4",
            vec![
                190.44236969414825,
                190.4344384721956,
                252.59949716835982,
                254.91723064636983,
                0.0034003170790442797,
                0.001766278153469831,
                -0.00266312569781606,
                0.0003299517423931039,
            ],
        ),
        (
            "ucm",
            vec![
                833.006, 830.345, 373.850, 253.749, 0.80065662, -0.33518, 0.13211, 0.00055, 0.00057,
            ],
        ),
    ];
    for (n, (cam, (name, p))) in rig.cameras.iter().zip(expect).enumerate() {
        assert_eq!(params_of(lens_of(cam)), (name, p));
        assert_eq!((cam.id, cam.img_dir.clone()), (n as u32, format!("cam{n}")));
    }
    assert_eq!(
        (rig.cameras[2].model.width(), rig.cameras[2].model.height()),
        (752, 480)
    );
    // Camera 0's frame is the rig frame; the others as the chain was made.
    assert_eq!(
        rig.cameras[0].pose,
        Pose {
            rvec: [0.0; 3],
            t_m: [0.0; 3]
        }
    );
    let want1 = Pose {
        rvec: [0.0044, -0.0007, 0.0008],
        t_m: [0.1011, 0.0020, -0.0010],
    };
    let want2 = Pose {
        rvec: [0.02, 1.5, -0.03],
        t_m: [0.05, 0.01, -0.08],
    };
    assert_same_pose(&rig.cameras[1].pose, &want1, 1e-9);
    assert_same_pose(&rig.cameras[2].pose, &want2, 1e-9);
}

/// Basalt's unified model, `m = (x, y) / (alpha d + (1 - alpha) z)`, as Basalt computes it.
fn basalt_ucm_pixel(f: [f64; 4], alpha: f64, p: &Vector3<f64>) -> (f64, f64) {
    let den = alpha * p.norm() + (1.0 - alpha) * p.z;
    (f[0] * p.x / den + f[2], f[1] * p.y / den + f[3])
}

#[test]
fn basalt_ucm_projects_as_basalt_does() {
    let (f, alpha) = ([372.5, 371.75, 639.25, 479.5], 0.63);
    let text = format!(
        r#"{{"value0": {{"T_imu_cam": [{{"px": 0, "py": 0, "pz": 0, "qx": 0, "qy": 0, "qz": 0, "qw": 1}}],
        "intrinsics": [{{"camera_type": "ucm", "intrinsics": {{"fx": {}, "fy": {}, "cx": {}, "cy": {}, "alpha": {alpha}}}}}],
        "resolution": [[1280, 960]]}}}}"#,
        f[0], f[1], f[2], f[3]
    );
    let rig = parse_basalt_calibration(Path::new("calibration.json"), &text).unwrap();
    let cam = &rig.cameras[0];
    for deg in [0.0, 10.0, 45.0, 80.0, 100.0, 115.0] {
        for az in [0.3, 1.9, 4.0] {
            let a = f64::to_radians(deg);
            let p = Vector3::new(a.sin() * f64::cos(az), a.sin() * f64::sin(az), a.cos()) * 2.5;
            let px = cam.model.project(&p).unwrap();
            let (col, row) = basalt_ucm_pixel(f, alpha, &p);
            assert!(
                (px.col - col).abs() < 1e-9 && (px.row - row).abs() < 1e-9,
                "{deg} {az}"
            );
        }
    }
}

#[test]
fn basalt_round_trip_keeps_every_model() {
    let rig = basalt_rig();
    let text = basalt_calibration_json(&rig).unwrap();
    for key in [
        "calib_accel_bias",
        "calib_gyro_bias",
        "imu_update_rate",
        "accel_noise_std",
        "gyro_noise_std",
        "accel_bias_std",
        "gyro_bias_std",
        "cam_time_offset_ns",
        "vignette",
    ] {
        assert!(text.contains(&format!("\"{key}\"")), "{key}");
    }
    let back = parse_basalt_calibration(Path::new("calibration.json"), &text).unwrap();
    assert_eq!(back.len(), rig.len());
    for (a, b) in rig.cameras.iter().zip(&back.cameras) {
        if matches!(lens_of(a), Lens::Unified(_)) {
            // Through Basalt's alpha: within a unit or two in the last place.
            assert_same_intrinsics(a, b, 1e-15);
        } else {
            assert_eq!(a.model, b.model, "bit for bit");
        }
        assert_same_pose(&a.pose, &b.pose, 1e-9);
        assert_eq!(a.id, b.id);
    }
    // Read, write, read: the ucm camera's parameters settle.
    let again = parse_basalt_calibration(
        Path::new("calibration.json"),
        &basalt_calibration_json(&back).unwrap(),
    )
    .unwrap();
    for (a, b) in back.cameras.iter().zip(&again.cameras) {
        assert_same_intrinsics(a, b, 1e-15);
    }
}

#[test]
fn kalibr_round_trip_keeps_every_model_in_cam0_frame() {
    let rig = kalibr_rig();
    let text = kalibr_camchain_yaml(&rig).unwrap();
    assert!(text.contains("intrinsics: ["), "flow lists:\n{text}");
    let back = parse_kalibr_camchain(Path::new("camchain.yaml"), &text).unwrap();
    assert_eq!(back.len(), rig.len());
    let cam0_from_rig = rig.cameras[0].rig_from_cam.inverse();
    for (a, b) in rig.cameras.iter().zip(&back.cameras) {
        assert_eq!(a.model, b.model, "bit for bit");
        // The rig re-expressed in camera 0's frame.
        assert_same_isometry(&(cam0_from_rig * a.rig_from_cam), &b.rig_from_cam, 1e-9);
    }
    assert_same_relative_poses(&rig, &back, 1e-9);
    assert_eq!(back.cameras[0].rig_from_cam, Isometry3::identity());
}

#[test]
fn config_basalt_kalibr_config_keeps_intrinsics_and_relative_poses() {
    let rig = basalt_rig();
    let config = parse_config_rig(
        Path::new("config.yaml"),
        &config_cameras_yaml(&rig).unwrap(),
    )
    .unwrap();
    let basalt = parse_basalt_calibration(
        Path::new("calibration.json"),
        &basalt_calibration_json(&config).unwrap(),
    )
    .unwrap();
    let kalibr = parse_kalibr_camchain(
        Path::new("camchain.yaml"),
        &kalibr_camchain_yaml(&basalt).unwrap(),
    )
    .unwrap();
    let end = parse_config_rig(
        Path::new("config.yaml"),
        &config_cameras_yaml(&kalibr).unwrap(),
    )
    .unwrap();
    for (a, b) in rig.cameras.iter().zip(&end.cameras) {
        assert_same_intrinsics(a, b, 1e-15);
        assert_eq!(
            a.model.max_fov_deg(),
            b.model.max_fov_deg(),
            "camera {}",
            a.id
        );
    }
    assert_same_relative_poses(&rig, &end, 1e-9);
}

#[test]
fn formats_are_told_apart_and_written_where_asked() {
    let dir = tempfile::tempdir().unwrap();
    let rig = basalt_rig();
    for (format, name) in [
        (RigFormat::ConfigYaml, "config.yaml"),
        (RigFormat::Basalt, "calibration.json"),
        (RigFormat::Kalibr, "left_right-camchain.yaml"),
    ] {
        // As a file of its own...
        let file = dir.path().join(format!("{}-{name}", format.name()));
        write_rig_file(&rig, format, &file).unwrap();
        assert_eq!(RigFormat::detect(&file).unwrap(), format);
        let (read, found, path) = read_rig_file(&file).unwrap();
        assert_eq!((found, path), (format, file.clone()));
        assert_same_relative_poses(&rig, &read, 1e-9);
        // ...and in a folder of its own.
        let folder = dir.path().join(format.name());
        std::fs::create_dir(&folder).unwrap();
        std::fs::copy(&file, folder.join(name)).unwrap();
        let (_, found, path) = read_rig_file(&folder).unwrap();
        assert_eq!((found, path), (format, folder.join(name)));
    }
    // A folder written in its usual name.
    let folder = dir.path().join("into");
    std::fs::create_dir(&folder).unwrap();
    write_rig_file(&rig, RigFormat::Basalt, &folder).unwrap();
    assert!(folder.join("calibration.json").is_file());
    assert_eq!(
        RigFormat::Basalt.rig_frame(),
        "Basalt's IMU frame (T_imu_cam)"
    );
    assert_eq!(RigFormat::Kalibr.rig_frame(), "cam0's frame (Kalibr)");
}

#[test]
fn ocam_txt_folders_are_read_in_centimetres_at_220_degrees() {
    let dir = tempfile::tempdir().unwrap();
    let pose = Pose {
        rvec: [0.0, 1.2, 0.0],
        t_m: [0.25, 0.0, -0.5],
    };
    let cam = Camera::new(
        1,
        "cam1",
        CameraModel::Ocam(sunny::sunny_cam1()),
        pose,
        None,
    );
    let rig = Rig::new(vec![cam]);
    let out = dir.path().join("released");
    write_rig_file(&rig, RigFormat::OcamTxt, &out).unwrap();
    for path in [out.clone(), out.join("ocam1.txt")] {
        assert_eq!(RigFormat::detect(&path).unwrap(), RigFormat::OcamTxt);
        let (read, format, file) = read_rig_file(&path).unwrap();
        assert_eq!((format, file), (RigFormat::OcamTxt, out.clone()));
        assert_eq!(read.cameras[0].model, rig.cameras[0].model);
        assert_eq!(read.cameras[0].model.max_fov_deg(), 220.0);
        assert_same_pose(&read.cameras[0].pose, &pose, 1e-12);
    }
}
