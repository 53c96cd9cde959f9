#![allow(clippy::unwrap_used)]
//! The lookup table against independent golden values computed from
//! `FORMATS.md` by `scripts/lut_golden/make_lut_golden.py` (numpy), on both
//! real sample rigs.

use std::path::{Path, PathBuf};

use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet};

fn samples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/omnimvs-samples")
}

/// Golden entries: `[cam][sphere][row/8][col/16]` -> `(col, row)` pixels,
/// `None` = invalid.
pub struct Golden {
    pub spheres: Vec<usize>,
    pub shape: [usize; 4],
    pub row_step: usize,
    pub col_step: usize,
    pub values: Vec<f32>,
}

impl Golden {
    pub fn load(name: &str) -> Self {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
        let meta: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap(),
        )
        .unwrap();
        let list = |key: &str| -> Vec<usize> {
            meta[key]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap() as usize)
                .collect()
        };
        let shape = list("shape");
        let bytes = std::fs::read(dir.join(format!("{name}.f32"))).unwrap();
        let values = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Self {
            spheres: list("spheres"),
            shape: [shape[0], shape[1], shape[2], shape[3]],
            row_step: meta["row_step"].as_u64().unwrap() as usize,
            col_step: meta["col_step"].as_u64().unwrap() as usize,
            values,
        }
    }

    pub fn at(&self, cam: usize, s: usize, r: usize, c: usize) -> Option<(f64, f64)> {
        let [_, ns, nr, nc] = self.shape;
        let i = (((cam * ns + s) * nr + r) * nc + c) * 2;
        let (col, row) = (self.values[i], self.values[i + 1]);
        (!col.is_nan()).then_some((f64::from(col), f64::from(row)))
    }
}

/// Compares a table with the golden values: returns (worst pixel error over
/// valid entries, number of valid entries compared).
pub fn compare(lut: &LookupTable, golden: &Golden) -> (f64, usize) {
    let (mut worst, mut n) = (0f64, 0usize);
    let [cams, ns, nr, nc] = golden.shape;
    assert_eq!(cams, lut.num_cameras());
    for cam in 0..cams {
        for (s, &sphere) in golden.spheres.iter().enumerate().take(ns) {
            for r in 0..nr {
                for c in 0..nc {
                    let (row, col) = (r * golden.row_step, c * golden.col_step);
                    let plane = lut.plane(cam, sphere);
                    let k = (row * lut.grid.width + col) * 2;
                    // The reference's invalid marker normalises far below -1.
                    let ours_invalid = plane[k] < -2.0 || plane[k + 1] < -2.0;
                    match golden.at(cam, s, r, c) {
                        None => assert!(
                            ours_invalid,
                            "cam {cam} sphere {sphere} ({row},{col}) should be invalid"
                        ),
                        Some((gc, gr)) => {
                            assert!(
                                !ours_invalid,
                                "cam {cam} sphere {sphere} ({row},{col}) should be valid"
                            );
                            let (oc, or) = lut.pixel(cam, sphere, row, col);
                            worst = worst.max(((oc - gc).powi(2) + (or - gr).powi(2)).sqrt());
                            n += 1;
                        }
                    }
                }
            }
        }
    }
    (worst, n)
}

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
