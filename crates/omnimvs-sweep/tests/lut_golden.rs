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
