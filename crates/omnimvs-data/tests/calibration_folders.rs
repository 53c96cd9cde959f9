//! Dataset folders described by a calibration tool's file (Basalt's `calibration.json`,
//! Kalibr's `camchain.yaml`, a `config.yaml` with only `cameras:`) and laid out as recordings
//! are: camera folders from 0 or 1, unpadded names, JPEG, colour, masks beside the images.

#![allow(clippy::unwrap_used, clippy::expect_used)] // helpers of tests

use std::path::Path;

use omnimvs_camera::{
    Camera, CameraModel, CentralCamera, FrameChoice, KannalaBrandt4, Lens, Pose, Rig, RigFormat,
    write_rig_file,
};
use omnimvs_data::{Dataset, OpenOptions};

const W: u32 = 64;
const H: u32 = 48;

/// Three Kannala-Brandt cameras 120 degrees apart, 0.2 m from a centre that sits 0.1 m below
/// and 0.3 m beside the calibration frame's origin, tilted 0.2 rad about x.
fn tilted_rig() -> Rig {
    let frame_from_ring = omnimvs_camera::nalgebra::Isometry3::new(
        omnimvs_camera::nalgebra::Vector3::new(0.3, 0.1, 0.0),
        omnimvs_camera::nalgebra::Vector3::new(0.2, 0.0, 0.0),
    );
    let lens = KannalaBrandt4::new(14.0, 14.0, 31.5, 23.5, 0.01, 0.0, 0.0, 0.0).unwrap();
    let model =
        CameraModel::Central(CentralCamera::new(Lens::KannalaBrandt4(lens), W, H, None).unwrap());
    let cameras = (0..3)
        .map(|i| {
            let yaw = 2.0 * std::f64::consts::PI / 3.0 * f64::from(i);
            let ring_from_cam = omnimvs_camera::nalgebra::Isometry3::new(
                omnimvs_camera::nalgebra::Vector3::new(0.2 * yaw.sin(), 0.0, 0.2 * yaw.cos()),
                omnimvs_camera::nalgebra::Vector3::new(0.0, yaw, 0.0),
            );
            let pose = Pose::from_isometry(&(frame_from_ring * ring_from_cam));
            Camera::new(i, format!("cam{i}"), model.clone(), pose, None)
        })
        .collect();
    Rig::new(cameras)
}

/// The same rig: models, ids and folders exact, poses to 1e-12 (a rotation read back through
/// a quaternion may differ in the last bit).
fn assert_same_rig(a: &Rig, b: &Rig) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.cameras.iter().zip(&b.cameras) {
        assert_eq!((x.id, &x.img_dir, &x.model), (y.id, &y.img_dir, &y.model));
        for (u, v) in x.pose.to_array().iter().zip(y.pose.to_array()) {
            assert!((u - v).abs() < 1e-12, "{:?} {:?}", x.pose, y.pose);
        }
    }
}

/// Writes a `W x H` image at `path`: gray, or colour with a different value per channel.
fn write_image(path: &Path, colour: bool) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    if colour {
        image::RgbImage::from_fn(W, H, |x, _| image::Rgb([x as u8 * 3, 60, 200]))
            .save(path)
            .unwrap();
    } else {
        image::GrayImage::from_fn(W, H, |x, y| image::Luma([(x + y) as u8]))
            .save(path)
            .unwrap();
    }
}

/// A folder with `rig` in `format`, `cam{first}..` holding frames `names` (e.g. `7.jpg`).
fn recording(rig: &Rig, format: RigFormat, first: u32, names: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let file = match format {
        RigFormat::Basalt => "calibration.json",
        RigFormat::Kalibr => "camchain.yaml",
        _ => "config.yaml",
    };
    write_rig_file(rig, format, &dir.path().join(file)).unwrap();
    for c in 0..rig.len() as u32 {
        for name in names {
            write_image(&dir.path().join(format!("cam{}/{name}", first + c)), c == 1);
        }
    }
    dir
}

#[test]
fn a_basalt_recording_with_unpadded_jpegs_from_cam0_opens() {
    let rig = tilted_rig();
    let dir = recording(&rig, RigFormat::Basalt, 0, &["7.jpg", "8.jpg", "10.jpg"]);
    let ds = Dataset::open(dir.path()).unwrap();
    assert_same_rig(&ds.rig, &rig);
    assert_eq!(ds.first_camera_number, 0);
    assert_eq!(ds.config.img_fmt, "cam%d/%d.jpg");
    assert_eq!(ds.frames_found(), [7, 8, 10]);
    assert_eq!(ds.config.min_depth_m, omnimvs_data::RELEASED_MIN_DEPTH_M);
    assert!(
        ds.found.rig.contains("calibration.json (basalt)"),
        "{:?}",
        ds.found
    );
    assert!(ds.frame.describe().contains("IMU"), "{:?}", ds.frame);
    // Camera 2's images are colour: read as gray (the channels' mean), at the camera's size.
    let frame = ds.read_frame(8).unwrap();
    assert_eq!(frame.len(), 3);
    assert_eq!((frame[1].width, frame[1].height), (W as usize, H as usize));
    let expected = (0.0 + 60.0 + 200.0) / 3.0;
    assert!(
        (frame[1].data[0] - expected).abs() < 1.0,
        "{}",
        frame[1].data[0]
    );
    // The folder was only read.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 4, "{names:?}");
}

#[test]
fn a_rig_mixing_gray_and_colour_cameras_reads_gray_ones_as_r_g_b() {
    let rig = tilted_rig();
    let dir = recording(&rig, RigFormat::Kalibr, 0, &["1.png"]);
    let ds = Dataset::open(dir.path()).unwrap();
    let colour = ds
        .read_colour_frame(1)
        .unwrap()
        .expect("camera 2 is colour");
    let gray = ds.read_frame(1).unwrap();
    assert_eq!(colour.len(), 3);
    for (c, image) in colour.iter().enumerate() {
        let [r, g, b] = &image.planes;
        if c == 1 {
            // The file's channels: x * 3, 60, 200.
            assert_eq!((r.data[5], g.data[5], b.data[5]), (15.0, 60.0, 200.0));
        } else {
            assert_eq!((r, g, b), (&gray[c], &gray[c], &gray[c]), "camera {c}");
        }
    }
}

#[test]
fn a_kalibr_recording_from_cam1_in_the_fitted_frame() {
    let rig = tilted_rig();
    let dir = recording(&rig, RigFormat::Kalibr, 1, &["00001.png", "00002.png"]);
    let options = OpenOptions {
        frame: FrameChoice::Fitted,
        min_depth_m: Some(0.4),
        ..OpenOptions::default()
    };
    let ds = Dataset::open_with(dir.path(), &options).unwrap();
    assert_eq!(ds.first_camera_number, 1);
    assert_eq!(ds.config.img_fmt, "cam%d/%05d.png");
    assert_eq!(ds.frames_found(), [1, 2]);
    assert_eq!(ds.config.min_depth_m, 0.4);
    assert_eq!(ds.frame.choice, "fitted");
    // Fitted: the cameras around the origin, level (y = 0), 0.2 m out, whatever the
    // calibration frame (Kalibr's: cam0's).
    for cam in &ds.rig.cameras {
        let c = cam.center_in_rig();
        assert!(c.y.abs() < 1e-9, "{c:?}");
        assert!(((c.x * c.x + c.z * c.z).sqrt() - 0.2).abs() < 1e-9, "{c:?}");
    }
    assert!(
        ds.frame
            .frame_from_calibration
            .iter()
            .any(|v| v.abs() > 0.1)
    );
}

#[test]
fn masks_beside_the_images_are_read_and_checked() {
    let rig = tilted_rig();
    let dir = recording(&rig, RigFormat::Basalt, 0, &["1.png"]);
    // Camera 1: left half invalid (zero), right half valid.
    image::GrayImage::from_fn(W, H, |x, _| image::Luma([if x < W / 2 { 0 } else { 255 }]))
        .save(dir.path().join("cam0/mask.png"))
        .unwrap();
    let ds = Dataset::open(dir.path()).unwrap();
    assert_eq!(
        ds.rig.cameras[0].valid_mask.as_deref(),
        Some("cam0/mask.png")
    );
    assert!(
        ds.found.masks[0].contains("nonzero = valid"),
        "{:?}",
        ds.found.masks
    );
    assert_eq!(ds.found.masks[1], "field of view only");
    let masks = ds.masks().unwrap();
    assert!(!masks[0].is_valid(1, (H / 2) as i64));
    assert_eq!(
        masks[0].is_valid(W as i64 - 20, (H / 2) as i64),
        masks[1].is_valid(W as i64 - 20, (H / 2) as i64)
    );
    // A mask of the wrong size: an error naming the file and the sizes.
    image::GrayImage::new(W / 2, H)
        .save(dir.path().join("cam1/mask.png"))
        .unwrap();
    let ds = Dataset::open(dir.path()).unwrap();
    let err = ds.masks().unwrap_err().to_string();
    assert!(
        err.contains("cam1/mask.png") && err.contains("32x48") && err.contains("64x48"),
        "{err}"
    );
}

#[test]
fn a_config_yaml_of_cameras_alone_finds_its_images() {
    let rig = tilted_rig();
    let dir = recording(&rig, RigFormat::ConfigYaml, 0, &["3.png"]);
    let ds = Dataset::open(dir.path()).unwrap();
    assert_eq!(ds.rig.len(), 3);
    assert_eq!(ds.frames_found(), [3]);
    assert_eq!(ds.config.min_depth_m, omnimvs_data::RELEASED_MIN_DEPTH_M);
}

#[test]
fn bad_recordings_get_errors_naming_what_is_wrong() {
    let rig = tilted_rig();
    // A camera folder missing.
    let dir = recording(&rig, RigFormat::Basalt, 0, &["1.png"]);
    std::fs::remove_dir_all(dir.path().join("cam2")).unwrap();
    let err = Dataset::open(dir.path()).unwrap_err().to_string();
    assert!(err.contains("cam0..cam2 or cam1..cam3"), "{err}");
    // Images of another size than the calibration's resolution.
    let dir = recording(&rig, RigFormat::Basalt, 0, &["1.png"]);
    image::GrayImage::new(W + 2, H)
        .save(dir.path().join("cam2/1.png"))
        .unwrap();
    let ds = Dataset::open(dir.path()).unwrap();
    let err = ds.read_frame(1).unwrap_err().to_string();
    assert!(err.contains("cam2/1.png") && err.contains("66x48"), "{err}");
    // A pose unit for a file whose translations are metres.
    let options = OpenOptions {
        pose_unit: Some(omnimvs_camera::LengthUnit::Centimetre),
        ..OpenOptions::default()
    };
    let err = Dataset::open_with(dir.path(), &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("calibration.json") && err.contains("metres"),
        "{err}"
    );
    // A fitted frame for two cameras.
    let two = Rig::new(rig.cameras[..2].to_vec());
    let dir = recording(&two, RigFormat::Basalt, 0, &["1.png"]);
    let options = OpenOptions {
        frame: FrameChoice::Fitted,
        ..OpenOptions::default()
    };
    let err = Dataset::open_with(dir.path(), &options)
        .unwrap_err()
        .to_string();
    assert!(err.contains("three cameras"), "{err}");
}

#[test]
fn a_rig_alone_opens_without_images() {
    let rig = tilted_rig();
    let dir = tempfile::tempdir().unwrap();
    write_rig_file(
        &rig,
        RigFormat::Basalt,
        &dir.path().join("calibration.json"),
    )
    .unwrap();
    assert!(Dataset::open(dir.path()).is_err());
    let options = OpenOptions {
        rig_only: true,
        ..OpenOptions::default()
    };
    let ds = Dataset::open_with(&dir.path().join("calibration.json"), &options).unwrap();
    assert_same_rig(&ds.rig, &rig);
    assert!(ds.frames_found().is_empty());
}
