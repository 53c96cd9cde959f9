//! Rigs of any calibration tool: `omnimvs rig show` and `rig convert` between the formats,
//! `info` on a recording laid out as a calibration tool leaves it, and a generated dataset of a
//! three-camera Kalibr rig in the fitted frame through `synth`, `info`, `sgm` and `infer`, and one of
//! lenses with tangential distortion.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]

mod support;

use std::path::{Path, PathBuf};

use omnimvs_camera::{Rig, read_rig_file};
use support::{omnimvs, run_ok, text};

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/rigs")
        .join(name)
}

/// Same intrinsics and the same pose of every camera relative to the first, to 1e-9.
fn assert_same_relative_rig(a: &Rig, b: &Rig) {
    assert_eq!(a.len(), b.len());
    let a0 = a.cameras[0].rig_from_cam.inverse();
    let b0 = b.cameras[0].rig_from_cam.inverse();
    for (x, y) in a.cameras.iter().zip(&b.cameras) {
        assert_eq!(x.model, y.model);
        let rel_x = (a0 * x.rig_from_cam).to_homogeneous();
        let rel_y = (b0 * y.rig_from_cam).to_homogeneous();
        assert!((rel_x - rel_y).abs().max() < 1e-9, "{rel_x} {rel_y}");
    }
}

/// Frame 1 of a `things` set through `rig` at 320x320 into `data` (`global`: options before
/// the command).
fn synth_one_frame(global: &[&str], rig: &Path, seed: &str, data: &Path, cache: &Path) {
    let mut args = global.to_vec();
    args.extend([
        "synth",
        "--kind",
        "things",
        "--rig",
        rig.to_str().unwrap(),
        "--size",
        "320x320",
        "--frames",
        "1",
        "--seed",
        seed,
        "--out",
        data.to_str().unwrap(),
    ]);
    run_ok(&args, cache);
}

/// Runs `sgm` on frame 1 of `data` at 80x320, N = 48 (with `extra` options) into `out` and
/// checks that it finds the depth: under 0.8 times the error of the best constant answer (a
/// broken matcher is at the constant's error or worse). Returns `sgm.json`.
fn sgm_finds_the_depth(data: &Path, out: &Path, extra: &[&str], cache: &Path) -> serde_json::Value {
    let mut args = vec![
        "sgm",
        data.to_str().unwrap(),
        "--frames",
        "1",
        "--size",
        "80x320",
        "--ndepth",
        "48",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let table = run_ok(&args, cache);
    assert!(table.contains("ZNCC+SGM"), "{table}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sgm.json")).unwrap()).unwrap();
    let ds = omnimvs_data::Dataset::open(data).unwrap();
    let spec = ds.sweep_spec(80, 320, 45.0, 48).unwrap();
    let truth = ds.eval_truth(1, &spec).unwrap().unwrap();
    let constant = support::constant_guess_mae(&truth, 48);
    let mae = summary["mean_metrics"]["mae"].as_f64().unwrap();
    println!(
        "{}: SGM MAE {mae:.2}, best constant {constant:.2}",
        data.display()
    );
    assert!(mae < 0.8 * constant, "MAE {mae}, constant {constant}");
    summary
}

#[test]
fn rig_convert_round_trips_through_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let kalibr = example("eucm-3cam/camchain.yaml");
    let (original, _, _) = read_rig_file(&kalibr).unwrap();
    let basalt = dir.path().join("calibration.json");
    let config = dir.path().join("rig.yaml");
    let back = dir.path().join("back-camchain.yaml");
    for (from, to) in [(&kalibr, &basalt), (&basalt, &config), (&config, &back)] {
        let out = run_ok(
            &[
                "rig",
                "convert",
                from.to_str().unwrap(),
                to.to_str().unwrap(),
            ],
            &cache,
        );
        assert!(out.contains("wrote"), "{out}");
        let (rig, _, _) = read_rig_file(to).unwrap();
        assert_same_relative_rig(&rig, &original);
    }
    // The Kalibr file written back reads as the original, in cam0's frame.
    let (back_rig, _, _) = read_rig_file(&back).unwrap();
    for (x, y) in back_rig.cameras.iter().zip(&original.cameras) {
        let d = (x.rig_from_cam.to_homogeneous() - y.rig_from_cam.to_homogeneous()).abs();
        assert!(d.max() < 1e-9);
    }
    // In the fitted frame: the cameras centred.
    let fitted = dir.path().join("fitted.yaml");
    run_ok(
        &[
            "--rig-frame",
            "fitted",
            "rig",
            "convert",
            kalibr.to_str().unwrap(),
            fitted.to_str().unwrap(),
        ],
        &cache,
    );
    let (rig, _, _) = read_rig_file(&fitted).unwrap();
    let mean: f64 = rig
        .cameras
        .iter()
        .map(|c| c.center_in_rig().coords)
        .sum::<omnimvs_camera::nalgebra::Vector3<f64>>()
        .norm();
    assert!(mean < 1e-9, "{mean}");
    assert_same_relative_rig(&rig, &original);
}

#[test]
fn rig_convert_refuses_a_model_the_format_lacks_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sunny.json");
    let sunny = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/sunny_single/config.yaml");
    let o = omnimvs(
        &[
            "rig",
            "convert",
            sunny.to_str().unwrap(),
            out.to_str().unwrap(),
        ],
        &dir.path().join("cache"),
    );
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.contains("sunny.json") && err.contains("cameras[0].model") && err.contains("ocam"),
        "{err}"
    );
    assert!(!out.exists());
    // An unknown output name asks for --to.
    let o = omnimvs(
        &["rig", "convert", sunny.to_str().unwrap(), "rig.txt"],
        &dir.path().join("cache"),
    );
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("--to"), "{}", text(&o.stderr));
}

#[test]
fn rig_show_prints_models_fields_of_view_frame_and_baselines() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_ok(
        &["rig", "show", example("kb4-6cam-240").to_str().unwrap()],
        &dir.path().join("cache"),
    );
    assert!(out.contains("cameras      6"), "{out}");
    assert!(
        out.contains("(id 6, kb4): 800x800 px, FOV 240.0 deg"),
        "{out}"
    );
    assert!(
        out.contains("frame        the rig frame of config.yaml"),
        "{out}"
    );
    assert!(out.contains("camera 1-2: 0.300 m"), "{out}");
    let out = run_ok(
        &["rig", "show", example("ds-4cam-compact").to_str().unwrap()],
        &dir.path().join("cache"),
    );
    assert!(out.contains("(basalt)") && out.contains("IMU"), "{out}");
    assert!(out.contains("camera 1-3: 0.070 m"), "{out}");
}

#[test]
fn a_generated_three_camera_kalibr_rig_runs_through_synth_info_sgm_and_infer() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = dir.path().join("eucm3");
    let rig = example("eucm-3cam/camchain.yaml");
    synth_one_frame(&["--rig-frame", "fitted"], &rig, "5", &data, &cache);
    let info = run_ok(&["info", data.to_str().unwrap()], &cache);
    assert!(info.contains("cameras      3"), "{info}");
    assert!(info.contains("(id 3, eucm): 320x320 px"), "{info}");
    assert!(info.contains("ground truth 1 of 1 frames"), "{info}");
    // Measured: SGM MAE 12.2 against the best constant's 17.2.
    let summary = sgm_finds_the_depth(&data, &dir.path().join("sgm"), &[], &cache);
    assert_eq!(summary["rig_frame"]["choice"], "calibration");
    // The bundled network runs on three cameras too; its picks, which read four cameras'
    // colours, stand aside and say so.
    let net = dir.path().join("net");
    let o = omnimvs(
        &[
            "infer",
            data.to_str().unwrap(),
            "--frames",
            "1",
            "--out",
            net.to_str().unwrap(),
        ],
        &cache,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("the bundled picks read 4 cameras and this rig has 3"),
        "{}",
        text(&o.stderr)
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(net.join("metrics.json")).unwrap()).unwrap();
    println!("three-camera rig, the default network: {metrics}");
    assert!(net.join("00001.tiff").is_file());
}

#[test]
fn info_on_a_basalt_recording_says_how_it_was_found() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let rec = dir.path().join("recording");
    std::fs::create_dir_all(&rec).unwrap();
    // The compact double-sphere rig's calibration, at a tenth of its image size.
    let (rig, _, _) = read_rig_file(&example("ds-4cam-compact")).unwrap();
    let small = Rig::new(
        rig.cameras
            .iter()
            .map(|c| {
                omnimvs_camera::Camera::new(
                    c.id,
                    c.img_dir.clone(),
                    c.model.resized(120, 120),
                    c.pose,
                    None,
                )
            })
            .collect(),
    );
    omnimvs_camera::write_rig_file(
        &small,
        omnimvs_camera::RigFormat::Basalt,
        &rec.join("calibration.json"),
    )
    .unwrap();
    for c in 0..4 {
        let cam = rec.join(format!("cam{c}"));
        std::fs::create_dir_all(&cam).unwrap();
        for f in [0, 1, 2] {
            image::GrayImage::new(120, 120)
                .save(cam.join(format!("{f}.jpg")))
                .unwrap();
        }
    }
    image::GrayImage::from_pixel(120, 120, image::Luma([255]))
        .save(rec.join("cam3/mask.png"))
        .unwrap();
    let info = run_ok(&["info", rec.to_str().unwrap()], &cache);
    assert!(
        info.contains("rig file     calibration.json (basalt)"),
        "{info}"
    );
    assert!(info.contains("frame        Basalt's IMU frame"), "{info}");
    assert!(
        info.contains("cam%d/%d.jpg with cameras numbered from 0, 3 frames found in cam0/"),
        "{info}"
    );
    assert!(
        info.contains("camera 4: cam3/mask.png (beside the images: nonzero = valid)"),
        "{info}"
    );
    assert!(info.contains("camera 1: field of view only"), "{info}");
    let fitted = run_ok(
        &["--rig-frame", "fitted", "info", rec.to_str().unwrap()],
        &cache,
    );
    assert!(
        fitted.contains("frame        fitted to the cameras"),
        "{fitted}"
    );
}

/// Four cameras of Kalibr's `omni` model with `radtan` distortion (not radial: the sweep
/// projects them through the exact model) on a square, 0.35 m apart, as Kalibr writes them.
fn omni_radtan_camchain() -> String {
    let distortions = [
        "[-0.05, 0.01, 0.001, -0.002]",
        "[0.02, -0.003, -0.0015, 0.001]",
        "[-0.03, 0.004, 0.0008, 0.0012]",
        "[0.01, 0.0, 0.002, -0.001]",
    ];
    let mut text = String::new();
    for (i, coeffs) in distortions.iter().enumerate() {
        text += &format!(
            "cam{i}:\n  camera_model: omni\n  intrinsics: [1.1, 260.0, 261.0, 319.5, 319.5]\n  \
             distortion_model: radtan\n  distortion_coeffs: {coeffs}\n  resolution: [640, 640]\n"
        );
        if i > 0 {
            // Each camera a quarter turn from the one before, 0.25 m along x and z.
            text += "  T_cn_cnm1:\n  - [0.0, 0.0, -1.0, -0.25]\n  - [0.0, 1.0, 0.0, 0.0]\n  \
                     - [1.0, 0.0, 0.0, -0.25]\n  - [0.0, 0.0, 0.0, 1.0]\n";
        }
    }
    text
}

#[test]
fn a_rig_of_lenses_with_tangential_distortion_runs_through_synth_and_sgm_with_point_clouds() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let camchain = dir.path().join("camchain.yaml");
    std::fs::write(&camchain, omni_radtan_camchain()).unwrap();
    let data = dir.path().join("omni");
    synth_one_frame(&[], &camchain, "6", &data, &cache);
    let info = run_ok(&["info", data.to_str().unwrap()], &cache);
    assert!(info.contains("(id 4, ucm): 320x320 px"), "{info}");
    // Measured: SGM MAE 8.05 against the best constant's 15.3.
    let out = dir.path().join("sgm");
    sgm_finds_the_depth(&data, &out, &["--ply"], &cache);
    // The point cloud: a header, then one point per grid pixel with a depth (most of them).
    let ply = std::fs::read(out.join("00001.ply")).unwrap();
    let header = String::from_utf8_lossy(&ply[..200.min(ply.len())]).to_string();
    let vertices: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .expect("vertex count")
        .parse()
        .unwrap();
    assert!(vertices > 80 * 320 / 2 && vertices <= 80 * 320, "{header}");
}

/// `omnimvs lut` needs the rig alone: a calibration file with no images beside it will do.
#[test]
fn lut_builds_from_a_calibration_file_alone() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    for (file, cameras) in [
        ("kb4-6cam-240/config.yaml", 6),
        ("ds-4cam-compact/calibration.json", 4),
        ("eucm-3cam/camchain.yaml", 3),
    ] {
        let out = dir.path().join("table.hwd");
        run_ok(
            &[
                "lut",
                example(file).to_str().unwrap(),
                "--size",
                "16x64",
                "--ndepth",
                "8",
                "--out",
                out.to_str().unwrap(),
            ],
            &cache,
        );
        let bytes = std::fs::metadata(&out).unwrap().len();
        assert_eq!(bytes, (cameras * 4 * 16 * 64 * 2 * 4) as u64, "{file}");
    }
}
