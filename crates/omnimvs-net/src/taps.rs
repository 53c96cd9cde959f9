//! Lookup-table grids and their bilinear taps, the geometry behind the sweep layer.
//!
//! A grid holds, for every sample `(sphere, row, col)` of the equirectangular output, the
//! position in a fisheye image normalised the way PyTorch's `grid_sample(align_corners=True)`
//! reads it (`x = col / (width - 1) * 2 - 1`, `y` likewise), so it applies to an image of any
//! size, in particular to the half-resolution feature maps. A tap is one of the four bilinear
//! neighbours of a sample with its weight; neighbours outside the source contribute zero, like
//! `grid_sample`'s zero padding.

use std::ops::Range;

use rayon::prelude::*;

use crate::error::NetError;

/// One camera's slice `[num_spheres, height, width, 2]` of a lookup table (`.hwd` layout).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepGrid {
    /// Number of swept spheres (`N / 2`).
    pub num_spheres: usize,
    /// Rows of the equirectangular grid.
    pub height: usize,
    /// Columns of the equirectangular grid.
    pub width: usize,
    /// Normalised `(x, y)` source positions, C order `[num_spheres, height, width, 2]`.
    pub coords: Vec<f32>,
}

impl SweepGrid {
    /// Wraps one camera's coordinates.
    ///
    /// # Errors
    /// [`NetError::Shape`] when `coords` does not hold `num_spheres * height * width * 2`
    /// values.
    pub fn new(
        num_spheres: usize,
        height: usize,
        width: usize,
        coords: Vec<f32>,
    ) -> Result<Self, NetError> {
        let expected = num_spheres * height * width * 2;
        if coords.len() != expected {
            return Err(NetError::Shape {
                what: "sweep grid coordinates".into(),
                expected: vec![num_spheres, height, width, 2],
                actual: vec![coords.len()],
            });
        }
        Ok(Self {
            num_spheres,
            height,
            width,
            coords,
        })
    }

    /// Splits a whole lookup table `[num_cameras, num_spheres, height, width, 2]` into one
    /// grid per camera.
    ///
    /// # Errors
    /// [`NetError::Shape`] when the length does not match.
    pub fn split_table(
        table: &[f32],
        num_cameras: usize,
        num_spheres: usize,
        height: usize,
        width: usize,
    ) -> Result<Vec<Self>, NetError> {
        let per_camera = num_spheres * height * width * 2;
        if table.len() != num_cameras * per_camera {
            return Err(NetError::Shape {
                what: "lookup table".into(),
                expected: vec![num_cameras, num_spheres, height, width, 2],
                actual: vec![table.len()],
            });
        }
        table
            .chunks_exact(per_camera)
            .map(|coords| Self::new(num_spheres, height, width, coords.to_vec()))
            .collect()
    }

    /// Samples per sphere, `height * width`.
    pub fn samples_per_sphere(&self) -> usize {
        self.height * self.width
    }

    /// Normalised position `(x, y)` of sample `index` (flat over spheres, rows, columns).
    pub fn coord(&self, index: usize) -> (f32, f32) {
        (self.coords[2 * index], self.coords[2 * index + 1])
    }
}

/// The four bilinear neighbours (north-west, north-east, south-west, south-east) of one
/// sample: flat indices `row * src_width + col` into the source and their weights. An
/// outside neighbour has index 0 and weight 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Taps {
    /// Flat source indices.
    pub index: [u32; 4],
    /// Bilinear weights; zero for neighbours outside the source.
    pub weight: [f32; 4],
}

impl Taps {
    /// Whether every neighbour lies outside the source (the sample is zero).
    pub fn is_empty(&self) -> bool {
        self.weight == [0.0; 4]
    }
}

/// Bilinear taps of the normalised position `(x, y)` in a `src_height x src_width` source,
/// computed in `f32` with the same formulas as PyTorch's `grid_sample` (bilinear, zero
/// padding, `align_corners=True`). Non-finite positions give empty taps.
#[inline]
pub fn bilinear_taps(x: f32, y: f32, src_height: usize, src_width: usize) -> Taps {
    let ix = (x + 1.0) / 2.0 * (src_width as f32 - 1.0);
    let iy = (y + 1.0) / 2.0 * (src_height as f32 - 1.0);
    let mut taps = Taps::default();
    if !(ix.is_finite() && iy.is_finite()) {
        return taps;
    }
    let ix_nw = floor(ix);
    let iy_nw = floor(iy);
    let (dx, dy) = (ix - ix_nw, iy - iy_nw);
    let (ex, ey) = (ix_nw + 1.0 - ix, iy_nw + 1.0 - iy);
    // The corners' columns and rows as integers (the floors are whole numbers, and any
    // beyond an i32 lies outside the source either way): the same tests as in `f32`.
    let (x0, y0) = (ix_nw as i64, iy_nw as i64);
    let (width, height) = (src_width as i64, src_height as i64);
    let corners = [
        (x0, y0, ex * ey),
        (x0 + 1, y0, dx * ey),
        (x0, y0 + 1, ex * dy),
        (x0 + 1, y0 + 1, dx * dy),
    ];
    for (k, (cx, cy, w)) in corners.into_iter().enumerate() {
        if (0..width).contains(&cx) && (0..height).contains(&cy) {
            taps.index[k] = (cy * width + cx) as u32;
            taps.weight[k] = w;
        }
    }
    taps
}

/// `value.floor()` for a finite `value`, without a call: the default x86-64 target has no
/// rounding instruction, so `f32::floor` is a library function, and the cascade takes
/// millions of taps a frame. Truncation toward zero, one less where that rounded up; exact for
/// every finite value whose floor fits an `i32`. Beyond that both answers lie outside any
/// image, so the taps they give are the same (empty).
#[inline]
fn floor(value: f32) -> f32 {
    let truncated = value as i32 as f32;
    if truncated > value {
        truncated - 1.0
    } else {
        truncated
    }
}

/// Taps of every sample of `grid` for a `src_height x src_width` source, flat over
/// `[num_spheres, height, width]`.
pub fn grid_taps(grid: &SweepGrid, src_height: usize, src_width: usize) -> Vec<Taps> {
    grid.coords
        .par_chunks_exact(2)
        .map(|xy| bilinear_taps(xy[0], xy[1], src_height, src_width))
        .collect()
}

/// Warps a feature map `[channels, src_height, src_width]` (C order) onto `spheres` of
/// `grid`, returning `[spheres.len(), channels, height, width]` (C order). Samples with
/// empty taps are skipped (they stay zero). Parallel over spheres; no gradient.
///
/// # Errors
/// [`NetError::Shape`] when `feature` does not hold `channels * src_height * src_width`
/// values or `spheres` is out of range.
pub fn warp_features(
    feature: &[f32],
    channels: usize,
    src_height: usize,
    src_width: usize,
    grid: &SweepGrid,
    spheres: Range<usize>,
) -> Result<Vec<f32>, NetError> {
    let plane = src_height * src_width;
    if feature.len() != channels * plane {
        return Err(NetError::Shape {
            what: "feature map".into(),
            expected: vec![channels, src_height, src_width],
            actual: vec![feature.len()],
        });
    }
    if spheres.start > spheres.end || spheres.end > grid.num_spheres {
        return Err(NetError::Shape {
            what: "sphere range".into(),
            expected: vec![grid.num_spheres],
            actual: vec![spheres.start, spheres.end],
        });
    }
    let (height, width) = (grid.height, grid.width);
    let per_sphere = channels * height * width;
    let mut out = vec![0.0f32; spheres.len() * per_sphere];
    out.par_chunks_mut(per_sphere)
        .enumerate()
        .for_each(|(k, out)| {
            let sphere = spheres.start + k;
            let mut row_taps = Vec::with_capacity(width);
            for row in 0..height {
                let first = (sphere * height + row) * width;
                row_taps.clear();
                row_taps.extend((0..width).map(|col| {
                    let (x, y) = grid.coord(first + col);
                    bilinear_taps(x, y, src_height, src_width)
                }));
                if row_taps.iter().all(Taps::is_empty) {
                    continue;
                }
                for c in 0..channels {
                    let src = &feature[c * plane..(c + 1) * plane];
                    let dst = &mut out[(c * height + row) * width..(c * height + row + 1) * width];
                    for (value, taps) in dst.iter_mut().zip(&row_taps) {
                        if taps.is_empty() {
                            continue;
                        }
                        let mut sum = 0.0;
                        for t in 0..4 {
                            sum += src[taps.index[t] as usize] * taps.weight[t];
                        }
                        *value = sum;
                    }
                }
            }
        });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inline_floor_is_f32_floor_on_finite_values() {
        // Integers, halves, values just off an integer, both signs, the ends of f32's exact
        // integers and beyond.
        let mut values = vec![
            0.0f32,
            1.0,
            -1.0,
            0.5,
            -0.5,
            1e-7,
            -1e-7,
            16_777_216.0,
            -16_777_217.0,
        ];
        for i in -3000..3000 {
            let v = i as f32 * 0.37;
            values.extend([
                v,
                v.next_up(),
                v.next_down(),
                v.round(),
                v.round().next_down(),
            ]);
        }
        for v in values {
            assert_eq!(floor(v), v.floor(), "{v}");
        }
        // Beyond an i32 the two differ, and both corners lie outside: the same (empty) taps.
        for x in [3e9f32, -3e9, 1e30, -1e30] {
            assert!(bilinear_taps(x, 0.0, 768, 800).is_empty(), "{x}");
            assert!(bilinear_taps(0.0, x, 768, 800).is_empty(), "{x}");
        }
    }

    #[test]
    fn taps_interpolate_inside_and_drop_outside_neighbours() {
        // 3 x 5 source; x = 0 is column 2, y = 0 is row 1 exactly.
        let taps = bilinear_taps(0.0, 0.0, 3, 5);
        assert_eq!(taps.index[0], 7);
        assert!((taps.weight[0] - 1.0).abs() < 1e-6);
        assert!(taps.weight[1..].iter().all(|w| w.abs() < 1e-6));
        // Halfway between columns 3 and 4 of the last row: the south neighbours are outside.
        let taps = bilinear_taps(0.75, 1.0, 3, 5);
        assert_eq!(&taps.index[..2], &[13, 14]);
        assert!((taps.weight[0] - 0.5).abs() < 1e-6 && (taps.weight[1] - 0.5).abs() < 1e-6);
        assert_eq!(&taps.weight[2..], &[0.0, 0.0]);
        // The reference marks invalid entries with a pixel of -1e5.
        assert!(bilinear_taps(-1e5, 0.0, 3, 5).is_empty());
        assert!(bilinear_taps(f32::NAN, 0.0, 3, 5).is_empty());
    }

    #[test]
    fn warp_reproduces_the_source_on_an_identity_grid() {
        let (h, w, c) = (4, 6, 2);
        let mut coords = Vec::new();
        for row in 0..h {
            for col in 0..w {
                coords.push(col as f32 / (w - 1) as f32 * 2.0 - 1.0);
                coords.push(row as f32 / (h - 1) as f32 * 2.0 - 1.0);
            }
        }
        let grid = SweepGrid::new(1, h, w, coords).unwrap();
        let feature: Vec<f32> = (0..c * h * w).map(|i| i as f32 * 0.5 - 3.0).collect();
        let out = warp_features(&feature, c, h, w, &grid, 0..1).unwrap();
        for (a, b) in out.iter().zip(&feature) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
        assert!(warp_features(&feature, c, h, w, &grid, 0..2).is_err());
    }
}
