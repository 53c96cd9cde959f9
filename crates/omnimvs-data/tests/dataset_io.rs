#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! Dataset folders, frames, ground-truth encodings and bad input, on the real
//! samples and on folders made in temporary directories.

use omnimvs_data::gt::{GT_WIDTH, InvDepthMap, read_inv_depth, write_inv_depth_tiff};
use omnimvs_data::image_io::write_png_u8;
use omnimvs_data::{DataError, Dataset, DatasetConfig, FrameRange, write_config_yaml};
use omnimvs_sweep::EquirectGrid;

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::samples;

/// A dataset folder with the sunny rig and `img_fmt`, but no images yet.
fn temp_dataset(img_fmt: &str) -> (tempfile::TempDir, Dataset) {
    let sunny = Dataset::open(&samples().join("sunny_single")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cfg = DatasetConfig {
        min_depth_m: 1.65,
        img_fmt: img_fmt.to_string(),
        frames: FrameRange {
            start: 1,
            step: 1,
            end: 3,
        },
        gt_fmt: None,
        split: None,
    };
    std::fs::write(
        dir.path().join("config.yaml"),
        write_config_yaml(&sunny.rig, &cfg).unwrap(),
    )
    .unwrap();
    let ds = Dataset::open(dir.path()).unwrap();
    (dir, ds)
}

#[test]
fn real_samples_frames_and_quirk() {
    // sunny_single names its frames cam%d/%04d.png.
    let sunny = Dataset::open(&samples().join("sunny_single")).unwrap();
    assert_eq!(sunny.frames_found(), vec![1]);
    let imgs = sunny.read_frame(1).unwrap();
    assert_eq!(imgs.len(), 4);
    assert_eq!((imgs[0].width, imgs[0].height), (800, 768));
    // RGB -> gray by channel mean: values stay in [0, 255] and vary.
    let (min, max) = imgs[0]
        .data
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert!(min >= 0.0 && max <= 255.0 && max - min > 50.0);
    let itbt = Dataset::open(&samples().join("itbt_sample")).unwrap();
    assert_eq!(itbt.frames_found(), vec![1, 2, 3]);
    assert_eq!(itbt.read_image(2, 3).unwrap().width, 1600);
    // The 0001/00001 quirk: a 5-digit pattern finds 4-digit files.
    let mut quirk = sunny.clone();
    quirk.config.img_fmt = "cam%d/%05d.png".into();
    assert!(quirk.image_path(0, 1).unwrap().ends_with("cam1/0001.png"));
}

#[test]
fn config_round_trips_through_writer() {
    let sunny = Dataset::open(&samples().join("sunny_single")).unwrap();
    let (_dir, ds) = temp_dataset("cam%d/%05d.png");
    assert_eq!(ds.rig, sunny.rig);
    assert_eq!(ds.config.frames.indices(), vec![1, 2, 3]);
}

#[test]
fn normalisation_has_zero_mean_unit_variance_over_valid_pixels() {
    let sunny = Dataset::open(&samples().join("sunny_single")).unwrap();
    let img = sunny.read_image(0, 1).unwrap();
    let mask = &sunny.masks().unwrap()[0];
    let n = omnimvs_data::image_io::normalize_for_network(&img, Some(mask)).unwrap();
    let vals: Vec<f64> = n
        .data
        .iter()
        .zip(&mask.valid)
        .filter(|(_, v)| **v)
        .map(|(x, _)| f64::from(*x))
        .collect();
    let mean = vals.iter().sum::<f64>() / vals.len() as f64;
    let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vals.len() as f64;
    assert!(
        mean.abs() < 1e-4 && (var - 1.0).abs() < 1e-3,
        "mean {mean} var {var}"
    );
    assert!(n.data.iter().zip(&mask.valid).all(|(x, v)| *v || *x == 0.0));
}

#[test]
fn wrong_size_missing_and_corrupt_images() {
    let (dir, ds) = temp_dataset("cam%d/%05d.png");
    for c in 1..=4 {
        std::fs::create_dir_all(dir.path().join(format!("cam{c}"))).unwrap();
    }
    // Wrong size.
    let p = dir.path().join("cam1/00001.png");
    write_png_u8(&p, 10, 8, 1, &[0u8; 80]).unwrap();
    let e = ds.read_image(0, 1).unwrap_err();
    assert!(matches!(e, DataError::ImageSize { .. }));
    let msg = e.to_string();
    assert!(
        msg.contains("cam1/00001.png") && msg.contains("10x8") && msg.contains("800x768"),
        "{msg}"
    );
    // Missing frame: the error lists what was tried.
    let msg = ds.read_image(1, 2).unwrap_err().to_string();
    assert!(
        msg.contains("frame 2") && msg.contains("cam2/00002.png"),
        "{msg}"
    );
    assert!(!ds.has_frame(2));
    // Corrupt PNG.
    let p = dir.path().join("cam2/00001.png");
    std::fs::write(&p, b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let msg = ds.read_image(1, 1).unwrap_err().to_string();
    assert!(
        msg.contains("cam2/00001.png") && msg.contains("decode"),
        "{msg}"
    );
}

#[test]
fn config_errors_name_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let e = Dataset::open(dir.path()).unwrap_err().to_string();
    assert!(e.contains("config.yaml"), "{e}");
    let sunny = std::fs::read_to_string(samples().join("sunny_single/config.yaml")).unwrap();
    let bad = sunny.replace(
        "omnimvs_sweep_min_depth: 1.65",
        "omnimvs_sweep_min_depth: -1",
    );
    std::fs::write(dir.path().join("config.yaml"), bad).unwrap();
    let e = Dataset::open(dir.path()).unwrap_err().to_string();
    assert!(e.contains("config.omnimvs_sweep_min_depth"), "{e}");
    let bad = sunny.replace("\"cam%d/%04d.png\"", "\"cam%s/%04d.png\"");
    std::fs::write(dir.path().join("config.yaml"), bad).unwrap();
    let e = Dataset::open(dir.path()).unwrap_err().to_string();
    assert!(e.contains("dataset.img_fmt"), "{e}");
    // Truncated in the middle of the cameras list.
    let cut = &sunny[..sunny.find("  - cam_id: 2").unwrap() - 200];
    std::fs::write(dir.path().join("config.yaml"), cut).unwrap();
    let e = Dataset::open(dir.path()).unwrap_err().to_string();
    // Cut inside a bracketed list: a YAML error with the line and column.
    assert!(
        e.contains("config.yaml") && e.contains("not valid YAML") && e.contains("line "),
        "{e}"
    );
}

fn ramp_map(h: usize) -> InvDepthMap {
    InvDepthMap {
        width: GT_WIDTH,
        height: h,
        data: (0..GT_WIDTH * h)
            .map(|i| (i % 997) as f32 / 997.0 * 1.8)
            .collect(),
    }
}

#[test]
fn ground_truth_in_three_encodings() {
    let dir = tempfile::tempdir().unwrap();
    let map = ramp_map(320);
    // 1. Multi-page TIFF: an 8-bit RGB thumbnail first, then the f32 page.
    let tiff_path = dir.path().join("00001.tiff");
    {
        use tiff::encoder::{TiffEncoder, colortype};
        let mut buf = std::io::Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut buf).unwrap();
        enc.write_image::<colortype::RGB8>(4, 2, &[128u8; 24])
            .unwrap();
        enc.write_image::<colortype::Gray32Float>(640, 320, &map.data)
            .unwrap();
        std::fs::write(&tiff_path, buf.into_inner()).unwrap();
    }
    assert_eq!(read_inv_depth(&tiff_path).unwrap(), map);
    // Our own single-page writer reads back bit for bit.
    let own = dir.path().join("own.tiff");
    write_inv_depth_tiff(&own, &map).unwrap();
    assert_eq!(read_inv_depth(&own).unwrap(), map);
    // 2. 16-bit PNG of the released sets.
    let png = dir.path().join("00001.png");
    let q: Vec<u16> = (0..640 * 160).map(|i| (i % 65501) as u16).collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(640, 160, q.clone())
        .unwrap()
        .save(&png)
        .unwrap();
    let m = read_inv_depth(&png).unwrap();
    assert_eq!((m.width, m.height), (640, 160));
    let want = f64::from(q[12345]) / 65500.0 / 0.55;
    assert!((f64::from(m.data[12345]) - want).abs() < 1e-6);
    // 3. Raw f32.
    let raw = dir.path().join("00001.bin");
    let bytes: Vec<u8> = map.data.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&raw, &bytes).unwrap();
    assert_eq!(read_inv_depth(&raw).unwrap(), map);
    std::fs::write(&raw, &bytes[..1000]).unwrap();
    let e = read_inv_depth(&raw).unwrap_err().to_string();
    assert!(
        e.contains("00001.bin") && e.contains("whole number of rows"),
        "{e}"
    );
    // An 8-bit PNG is not the released encoding.
    let png8 = dir.path().join("8bit.png");
    write_png_u8(&png8, 4, 4, 1, &[0u8; 16]).unwrap();
    assert!(
        read_inv_depth(&png8)
            .unwrap_err()
            .to_string()
            .contains("16-bit")
    );
}

#[test]
fn dataset_ground_truth_is_cropped_and_indexed() {
    let (dir, ds) = temp_dataset("cam%d/%05d.png");
    std::fs::create_dir_all(dir.path().join("omnidepth_gt_640")).unwrap();
    let mut map = ramp_map(320);
    // A constant 2 m band in the middle rows.
    for v in &mut map.data[150 * 640..170 * 640] {
        *v = 0.5;
    }
    write_inv_depth_tiff(&dir.path().join("omnidepth_gt_640/00002.tiff"), &map).unwrap();
    assert!(ds.gt_path(1).is_none());
    let hyps = ds.hypotheses(192).unwrap();
    let grid = |h, w, phi_deg| EquirectGrid::new(h, w, phi_deg).unwrap();
    let gt = ds
        .ground_truth(2, &grid(160, 640, 45.0), &hyps)
        .unwrap()
        .unwrap();
    assert_eq!(gt.index.len(), 160 * 640);
    // Row 80 of the crop is row 160 of the full map: inside the band.
    let n = gt.index[80 * 640 + 5];
    assert!((f64::from(n) - hyps.index(0.5)).abs() < 1e-3);
    // A smaller grid samples the full-resolution ground truth at its rays.
    let small = ds
        .ground_truth(2, &grid(40, 160, 45.0), &hyps)
        .unwrap()
        .unwrap();
    assert_eq!(small.index.len(), 40 * 160);
    assert_eq!(small.index[20 * 160 + 3], gt.index[80 * 640 + 12]);
    // Another latitude range at the map's own width is sampled at its rays, not cropped:
    // row 0 of a +-30 degree grid lies at latitude -30, row 106 of the +-90 degree map.
    let full = ds
        .ground_truth(2, &grid(320, 640, 90.0), &hyps)
        .unwrap()
        .unwrap();
    let narrow = ds
        .ground_truth(2, &grid(160, 640, 30.0), &hyps)
        .unwrap()
        .unwrap();
    assert_eq!(narrow.index[5], full.index[106 * 640 + 5]);
    assert_ne!(narrow.index[5], gt.index[5]);
    // A grid wider in latitude than the map cannot be served.
    let map160 = InvDepthMap {
        width: 640,
        height: 160,
        data: vec![0.5; 640 * 160],
    };
    write_inv_depth_tiff(&dir.path().join("omnidepth_gt_640/00003.tiff"), &map160).unwrap();
    assert!(ds.ground_truth(3, &grid(160, 320, 90.0), &hyps).is_err());
}

/// `config.yaml` is written by serialising a struct: read back by our reader it gives the same
/// rig (bit for bit, masks included), minimum depth, formats and frames as the file it was
/// made from, for both samples, with and without a ground-truth format.
#[test]
fn written_config_reads_back_the_same_dataset() {
    let path = std::path::Path::new("written/config.yaml");
    for name in ["sunny_single", "itbt_sample"] {
        let ds = Dataset::open(&samples().join(name)).unwrap();
        let split = omnimvs_data::Split {
            train: vec![1, 3],
            test: vec![2],
            gt_phi_deg: Some(90.0),
        };
        for (gt_fmt, split) in [
            (None, None),
            (Some("omnidepth_gt_640/%05d.tiff".to_string()), None),
            (Some("omnidepth_gt_640/%05d.tiff".to_string()), Some(split)),
        ] {
            let config = DatasetConfig {
                gt_fmt,
                split,
                ..ds.config.clone()
            };
            let text = write_config_yaml(&ds.rig, &config).unwrap();
            assert!(
                text.starts_with("# written by omnimvs\nconfig:\n  omnimvs_sweep_min_depth: "),
                "{text}"
            );
            assert!(text.contains("\ncameras:\n  - cam_id: 1\n"), "{text}");
            assert_eq!(DatasetConfig::parse(path, &text).unwrap(), config, "{name}");
            let rig = omnimvs_camera::parse_config_rig(path, &text).unwrap();
            assert_eq!(rig, ds.rig, "{name}");
        }
    }
}

/// A folder in the released datasets' layout (`ocamK.txt` + `poses.txt`, no `config.yaml`)
/// opens as the same rig and frames as the sample it was made from.
#[test]
fn released_layout_opens_without_config_yaml() {
    let sunny = Dataset::open(&samples().join("sunny_single")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    omnimvs_camera::write_ocam_txt_rig(&sunny.rig, dir.path()).unwrap();
    for camera in 1..=sunny.rig.len() {
        let from = sunny.image_path(camera - 1, 1).unwrap();
        std::fs::create_dir_all(dir.path().join(format!("cam{camera}"))).unwrap();
        std::fs::copy(&from, dir.path().join(format!("cam{camera}/0001.png"))).unwrap();
    }
    // A file that is not a numbered image does not count.
    std::fs::write(dir.path().join("cam1/notes.txt"), "x").unwrap();

    let released = Dataset::open(dir.path()).unwrap();
    assert_eq!(released.config.img_fmt, "cam%d/%04d.png");
    assert_eq!(released.config.frames, FrameRange::inclusive(1, 1));
    assert_eq!(
        released.config.min_depth_m,
        omnimvs_data::RELEASED_MIN_DEPTH_M
    );
    assert_eq!(released.rig.len(), sunny.rig.len());
    for (a, b) in released.rig.cameras.iter().zip(&sunny.rig.cameras) {
        assert_eq!(a.model, b.model);
        let (pa, pb) = (a.pose.to_array(), b.pose.to_array());
        assert!(
            pa.iter().zip(pb).all(|(x, y)| (x - y).abs() < 1e-12),
            "{pa:?} {pb:?}"
        );
    }
    assert_eq!(released.frames_found(), vec![1]);
    assert_eq!(
        released.read_frame(1).unwrap(),
        sunny.read_frame(1).unwrap()
    );

    // Without numbered images the error names the folder.
    let empty = tempfile::tempdir().unwrap();
    omnimvs_camera::write_ocam_txt_rig(&sunny.rig, empty.path()).unwrap();
    std::fs::create_dir_all(empty.path().join("cam1")).unwrap();
    let err = Dataset::open(empty.path()).unwrap_err().to_string();
    assert!(
        err.contains("cam1") && err.contains("numbered images"),
        "{err}"
    );
}
