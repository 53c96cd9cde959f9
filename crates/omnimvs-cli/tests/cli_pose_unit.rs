//! `--pose-unit`: a released-layout folder (`ocamK.txt` + `poses.txt`) states its translations
//! in centimetres (the released OmniMVS sets) unless told otherwise (millimetres in SweepNet's
//! `real_indoor_sample`); `omnimvs info` shows the rig it understood with baselines in metres,
//! and flags baselines no camera rig has, so a wrong unit is obvious.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
mod support;

use std::path::Path;

use omnimvs_data::Dataset;
use support::{omnimvs, run_ok, text};

/// The sunny sample in the released layout, its `poses.txt` translations multiplied by
/// `factor` (10: millimetres).
fn released_sunny(dir: &Path, factor: f64) {
    let sunny = Dataset::open(&samples::sample("sunny_single")).unwrap();
    std::fs::create_dir_all(dir).unwrap();
    omnimvs_camera::write_ocam_txt_rig(&sunny.rig, dir).unwrap();
    for camera in 1..=sunny.rig.len() {
        let from = sunny.image_path(camera - 1, 1).unwrap();
        std::fs::create_dir_all(dir.join(format!("cam{camera}"))).unwrap();
        std::fs::copy(&from, dir.join(format!("cam{camera}/00001.png"))).unwrap();
    }
    let poses = std::fs::read_to_string(dir.join("poses.txt")).unwrap();
    let scaled: String = poses
        .lines()
        .map(|line| {
            if line.starts_with('#') || line.trim().is_empty() {
                return format!("{line}\n");
            }
            let v: Vec<f64> = line
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            let t: Vec<String> = v[3..].iter().map(|t| format!("{:e}", t * factor)).collect();
            format!("{} {} {} {}\n", v[0], v[1], v[2], t.join(" "))
        })
        .collect();
    std::fs::write(dir.join("poses.txt"), scaled).unwrap();
}

#[test]
fn info_shows_the_rig_in_metres_for_the_stated_unit() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("released-mm");
    released_sunny(&data, 10.0);
    let cache = dir.path().join("cache");
    let path = data.to_str().unwrap();

    // Stated: the published rig, 0.849 and 1.200 m baselines, nothing flagged.
    let mm = run_ok(&["info", path, "--pose-unit", "mm"], &cache);
    assert!(mm.contains("translations read in mm"), "{mm}");
    assert!(mm.contains("camera 1-2: 0.849 m"), "{mm}");
    assert!(mm.contains("camera 1-3: 1.200 m"), "{mm}");
    assert!(!mm.contains("note:"), "{mm}");
    // The global option may come before the command too.
    assert_eq!(run_ok(&["--pose-unit", "mm", "info", path], &cache), mm);

    // Not stated: read as centimetres, ten times too far apart, and flagged.
    let cm = run_ok(&["info", path], &cache);
    assert!(cm.contains("translations read in cm"), "{cm}");
    assert!(cm.contains("camera 1-3: 12.000 m"), "{cm}");
    assert!(cm.contains("note:") && cm.contains("--pose-unit"), "{cm}");

    // The same unit reaches the other commands: the lookup table of the mm folder read in mm
    // is that of the same rig in centimetres read as such; read in cm it is not.
    let in_cm = dir.path().join("released-cm");
    released_sunny(&in_cm, 1.0);
    let lut = |data: &Path, extra: &[&str], name: &str| {
        let out = dir.path().join(name);
        let mut args = vec![
            "lut",
            data.to_str().unwrap(),
            "--size",
            "8x16",
            "--ndepth",
            "4",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        run_ok(&args, &cache);
        std::fs::read(&out).unwrap()
    };
    let reference = lut(&in_cm, &[], "cm.hwd");
    assert_eq!(lut(&data, &["--pose-unit", "mm"], "mm.hwd"), reference);
    assert_ne!(lut(&data, &[], "mm-as-cm.hwd"), reference);
}

#[test]
fn a_pose_unit_for_a_config_yaml_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sunny = samples::sample("sunny_single");
    let o = omnimvs(
        &["info", sunny.to_str().unwrap(), "--pose-unit", "cm"],
        &dir.path().join("cache"),
    );
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("--pose-unit cm"), "{err}");
    assert!(err.contains("config.yaml"), "{err}");
    assert!(err.contains("metres"), "{err}");
    // Metres, what a config.yaml holds, is accepted.
    run_ok(
        &["info", sunny.to_str().unwrap(), "--pose-unit", "m"],
        &dir.path().join("cache"),
    );
}

/// A command that would not apply the unit refuses it rather than ignoring it.
#[test]
fn a_command_that_would_ignore_the_unit_refuses_it() {
    let dir = tempfile::tempdir().unwrap();
    let o = omnimvs(
        &[
            "synth",
            "--kind",
            "things",
            "--frames",
            "1",
            "--out",
            dir.path().join("x").to_str().unwrap(),
            "--pose-unit",
            "mm",
        ],
        &dir.path().join("cache"),
    );
    assert_eq!(o.status.code(), Some(2));
    let err = text(&o.stderr);
    assert!(
        err.contains("--pose-unit mm") && err.contains("synth"),
        "{err}"
    );
    assert!(!dir.path().join("x").exists());
}
