//! Resampling a map from one equirectangular grid to another of the same latitude range.

use omnimvs_core::interp::mix_2d;

use crate::EquirectGrid;

/// Resamples a map on grid `from` at the rays of grid `to` (same latitude range): bilinear,
/// wrapping around in longitude, clamped in latitude. Both grids put their first and last
/// rows at `±phi_deg` and their column `c` at longitude `c / width`, so row `r` of `to` reads
/// row `r (h_from - 1) / (h_to - 1)` of `from` and column `c` reads column
/// `c w_from / w_to`. Used to carry one cascade stage's estimate to the next stage's grid
/// and to score a coarse output at a finer evaluation grid.
pub fn resample_map(map: &[f32], from: &EquirectGrid, to: &EquirectGrid) -> Vec<f32> {
    debug_assert_eq!(map.len(), from.len());
    let (hf, wf) = (from.height, from.width);
    let row_scale = if to.height > 1 {
        (hf as f64 - 1.0) / (to.height as f64 - 1.0)
    } else {
        0.0
    };
    let col_scale = wf as f64 / to.width as f64;
    let mut out = Vec::with_capacity(to.len());
    for row in 0..to.height {
        let r = (row as f64 * row_scale).clamp(0.0, hf as f64 - 1.0);
        let r0 = r.floor() as usize;
        let r1 = (r0 + 1).min(hf - 1);
        let fr = (r - r0 as f64) as f32;
        for col in 0..to.width {
            // Column centres: theta is linear in col / width on both grids.
            let c = (col as f64 * col_scale).rem_euclid(wf as f64);
            let c0 = c.floor() as usize % wf;
            let c1 = (c0 + 1) % wf;
            let fc = (c - c.floor()) as f32;
            let at = |r: usize, c: usize| map[r * wf + c];
            out.push(mix_2d(
                [at(r0, c0), at(r0, c1), at(r1, c0), at(r1, c1)],
                fc,
                fr,
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_keeps_constants_and_wraps_columns() {
        let from = EquirectGrid::new(4, 8, 45.0).unwrap();
        let to = EquirectGrid::new(8, 16, 45.0).unwrap();
        let constant = vec![3.5f32; from.len()];
        assert!(
            resample_map(&constant, &from, &to)
                .iter()
                .all(|&v| (v - 3.5).abs() < 1e-6)
        );
        // A map that is 1 in the last column only: the last target column lies halfway
        // between the last and the first source column (wrap-around).
        let mut map = vec![0f32; from.len()];
        for r in 0..4 {
            map[r * 8 + 7] = 1.0;
        }
        let out = resample_map(&map, &from, &to);
        assert!((out[15] - 0.5).abs() < 1e-6, "{}", out[15]);
        assert!((out[14] - 1.0).abs() < 1e-6, "{}", out[14]);
        assert!(out[0].abs() < 1e-6);
    }

    #[test]
    fn same_grid_is_the_identity_and_samples_land_on_the_same_rays() {
        let grid = EquirectGrid::new(5, 12, 45.0).unwrap();
        let map: Vec<f32> = (0..grid.len()).map(|v| v as f32 * 0.25).collect();
        assert_eq!(resample_map(&map, &grid, &grid), map);
        // A map linear in latitude and smooth in longitude: every target pixel gets the
        // value of its own ray (bilinear is exact for a function linear in row).
        let to = EquirectGrid::new(9, 12, 45.0).unwrap();
        let lat: Vec<f32> = (0..grid.len())
            .map(|i| grid.phi_rad((i / grid.width) as f64) as f32)
            .collect();
        let out = resample_map(&lat, &grid, &to);
        for (i, v) in out.iter().enumerate() {
            let want = to.phi_rad((i / to.width) as f64) as f32;
            assert!((v - want).abs() < 1e-6, "pixel {i}: {v} vs {want}");
        }
    }
}
