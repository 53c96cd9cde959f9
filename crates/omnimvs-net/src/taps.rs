//! Lookup-table grids and their bilinear taps, the geometry behind the sweep layer.
//!
//! A grid holds, for every sample `(sphere, row, col)` of the equirectangular output, the
//! position in a fisheye image normalised the way PyTorch's `grid_sample(align_corners=True)`
//! reads it (`x = col / (width - 1) * 2 - 1`, `y` likewise), so it applies to an image of any
//! size, in particular to the half-resolution feature maps. A tap is one of the four bilinear
//! neighbours of a sample with its weight; neighbours outside the source contribute zero, like
//! `grid_sample`'s zero padding.

use std::ops::Range;

use omnimvs_core::interp::BilinearTap;
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

/// Taps of every sample of `grid` for a `src_height x src_width` source, flat over
/// `[num_spheres, height, width]`.
pub fn grid_taps(grid: &SweepGrid, src_height: usize, src_width: usize) -> Vec<BilinearTap> {
    grid.coords
        .par_chunks_exact(2)
        .map(|xy| BilinearTap::grid_sample(xy[0], xy[1], src_height, src_width))
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
                    BilinearTap::grid_sample(x, y, src_height, src_width)
                }));
                if row_taps.iter().all(BilinearTap::is_empty) {
                    continue;
                }
                for c in 0..channels {
                    let src = &feature[c * plane..(c + 1) * plane];
                    let dst = &mut out[(c * height + row) * width..(c * height + row + 1) * width];
                    for (value, taps) in dst.iter_mut().zip(&row_taps) {
                        if taps.is_empty() {
                            continue;
                        }
                        *value = taps.apply(src);
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
