#![allow(clippy::unwrap_used)]
//! The lookup table against independent golden values computed from
//! `FORMATS.md` by `scripts/lut_golden/make_lut_golden.py` (numpy), on both
//! real sample rigs.

#[path = "support/golden.rs"]
mod golden;

use golden::{Golden, compare};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::samples;

#[test]
fn lut_matches_independent_golden_values_on_both_samples() {
    for name in ["sunny_single", "itbt_sample"] {
        let rig =
            omnimvs_camera::read_config_rig(&samples().join(name).join("config.yaml")).unwrap();
        let min_depth = if name == "sunny_single" { 1.65 } else { 0.5 };
        let grid = EquirectGrid::new(160, 640, 45.0).unwrap();
        let hyps = InvDepthHypotheses::new(192, min_depth).unwrap();
        let lut = LookupTable::build(&rig, &grid, &hyps, SphereSet::EveryOther).unwrap();
        assert_eq!(lut.num_spheres(), 96);
        let golden = Golden::load(name);
        let (worst, n) = compare(&lut, &golden);
        println!("{name}: {n} valid entries, worst difference {worst:.2e} px");
        assert!(n > 7_000, "{name}: too few valid entries compared ({n})");
        assert!(worst < 0.01, "{name}: worst difference {worst} px");
    }
}

/// The table's batched build gives every entry exactly as `normalized_position` computes it
/// one point at a time, on both sample rigs and on the sunny rig with closed-form lenses.
#[test]
fn build_equals_normalized_position_to_the_bit() {
    use omnimvs_camera::{CameraModel, CentralCamera, DoubleSphere, KannalaBrandt4, Lens};
    let sunny =
        omnimvs_camera::read_config_rig(&samples().join("sunny_single/config.yaml")).unwrap();
    let itbt = omnimvs_camera::read_config_rig(&samples().join("itbt_sample/config.yaml")).unwrap();
    let with_lens = |lens: Lens| {
        let mut rig = sunny.clone();
        for camera in &mut rig.cameras {
            camera.model = CameraModel::Central(
                CentralCamera::new(lens.clone(), 800, 768, Some(220.0)).unwrap(),
            );
        }
        rig
    };
    let ds = DoubleSphere::new(177.0, 177.0, 399.5, 383.5, -0.2, 0.6).unwrap();
    let kb4 = KannalaBrandt4::new(200.0, 200.0, 399.5, 383.5, -0.01, 0.002, 0.0, 0.0).unwrap();
    let rigs = [
        sunny.clone(),
        itbt,
        with_lens(Lens::DoubleSphere(ds)),
        with_lens(Lens::KannalaBrandt4(kb4)),
    ];
    // 37 columns: runs of the build that end inside a batch.
    let grid = EquirectGrid::new(20, 37, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(16, 0.5).unwrap();
    for rig in &rigs {
        let lut = LookupTable::build(rig, &grid, &hyps, SphereSet::All).unwrap();
        let rays = grid.rays();
        for (cam, camera) in rig.cameras.iter().enumerate() {
            let cam_from_rig = camera.rig_from_cam.inverse();
            let size = (camera.model.width(), camera.model.height());
            for n in 0..hyps.count {
                let depth_m = 1.0 / hyps.inv_depth(n as f64);
                let plane = lut.plane(cam, n);
                for (i, ray) in rays.iter().enumerate() {
                    let p_cam =
                        (cam_from_rig.rotation * ray) * depth_m + cam_from_rig.translation.vector;
                    let want = omnimvs_sweep::normalized_position(camera, size, &p_cam);
                    let got = [plane[2 * i], plane[2 * i + 1]];
                    assert_eq!(
                        got.map(f32::to_bits),
                        want.map(f32::to_bits),
                        "{} cam {cam} sphere {n} pixel {i}",
                        camera.model.name()
                    );
                }
            }
        }
    }
}

#[test]
fn hwd_round_trip_and_size_check() {
    let rig = omnimvs_camera::read_config_rig(&samples().join("sunny_single/config.yaml")).unwrap();
    let grid = EquirectGrid::new(16, 32, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(8, 1.65).unwrap();
    let lut = LookupTable::build(&rig, &grid, &hyps, SphereSet::EveryOther).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(omnimvs_sweep::hwd_file_name(16, 32, 8));
    lut.write_hwd(&path).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().len(),
        4 * 4 * 16 * 32 * 2 * 4
    );
    let back = LookupTable::read_hwd(&path, &rig, &grid, &hyps, SphereSet::EveryOther).unwrap();
    assert_eq!(back, lut);
    // A table for a different N does not fit: clear error naming the file.
    let wrong = InvDepthHypotheses::new(16, 1.65).unwrap();
    let err = LookupTable::read_hwd(&path, &rig, &grid, &wrong, SphereSet::EveryOther).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("lt_(16,32,8).hwd") && msg.contains("expected 131072"),
        "{msg}"
    );
    // Odd N cannot be halved.
    assert!(
        LookupTable::build(
            &rig,
            &grid,
            &InvDepthHypotheses::new(7, 1.0).unwrap(),
            SphereSet::EveryOther
        )
        .is_err()
    );
}

#[test]
fn cache_builds_once_then_hits() {
    let rig = omnimvs_camera::read_config_rig(&samples().join("itbt_sample/config.yaml")).unwrap();
    let grid = EquirectGrid::new(16, 32, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(8, 0.5).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cache = omnimvs_sweep::LutCache::new(dir.path().join("lut"));
    let (a, s1) = cache
        .load_or_build(&rig, &grid, &hyps, SphereSet::All)
        .unwrap();
    assert!(matches!(s1, omnimvs_sweep::CacheStatus::Built(_)), "{s1:?}");
    let (b, s2) = cache
        .load_or_build(&rig, &grid, &hyps, SphereSet::All)
        .unwrap();
    assert!(matches!(s2, omnimvs_sweep::CacheStatus::Hit(_)), "{s2:?}");
    assert_eq!(a, b);
    // A different rig gets a different file.
    let mut other = rig.clone();
    other.cameras[0].pose.t_m[0] += 0.01;
    assert_ne!(
        cache.path_for(&rig, &grid, &hyps, SphereSet::All),
        cache.path_for(&other, &grid, &hyps, SphereSet::All)
    );
}
