//! Golden lookup-table values of `scripts/lut_golden/make_lut_golden.py`,
//! shared by the sweep crate's tests and the CLI's `omnimvs lut` test.
#![allow(clippy::unwrap_used, dead_code)]

use std::path::Path;

use omnimvs_sweep::LookupTable;

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
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../omnimvs-sweep/tests/golden");
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
