//! Per-pixel helpers on an output panorama, shared by the cascade's stages and the learnt pick
//! after it: where each camera sees the point of an output ray at a per-pixel inverse depth
//! ([`PixelSampler`]), and window sums over the panorama that wrap in longitude (`box_sum`).
//!
//! A lookup table holds fixed spheres only; the refinement stages of the cascade test a few
//! hypotheses around each pixel's own estimate, so their positions are projected on the fly
//! through the camera model. For a grid ray `r` (rig frame) and inverse depth `d`, the point
//! `r / d` seen from a camera with `cam_from_rig = (R, t)` lies along `R r + d t`; only that
//! direction matters to a central projection, so `d = 0` (infinity) needs no special case. The
//! projection is ZNCC+SGM's [`SphereProjector`] (the camera's radial function tabulated in the
//! half angle: no `atan2`, no polynomial per sample), within about 1e-3 pixel of the exact
//! projection, and the normalisation is the lookup table's own
//! ([`omnimvs_sweep::normalized_pixel`]), so positions agree with the table on every sphere the
//! two share to 1e-5 (tested).

use std::ops::Range;

use omnimvs_camera::Rig;
use omnimvs_sweep::SphereProjector;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, normalized_pixel};
use rayon::prelude::*;

use crate::error::NetError;
use crate::taps::SweepGrid;

/// One camera's projection of the grid.
#[derive(Clone, Debug)]
struct CameraProjection {
    /// Image size `(width, height)` the positions are normalised by.
    size: (u32, u32),
    projector: SphereProjector,
}

/// Projects the rays of one output grid, at per-pixel inverse depths, into every camera of a
/// rig.
#[derive(Clone, Debug)]
pub struct PixelSampler {
    grid: EquirectGrid,
    hypotheses: InvDepthHypotheses,
    cameras: Vec<CameraProjection>,
}

impl PixelSampler {
    /// Prepares the rays of `grid` in every camera of `rig`; hypothesis indices are read with
    /// `hypotheses`.
    ///
    /// # Errors
    /// [`NetError::Stereo`] for a camera whose field of view is 360 degrees or more.
    pub fn new(
        rig: &Rig,
        grid: &EquirectGrid,
        hypotheses: &InvDepthHypotheses,
    ) -> Result<Self, NetError> {
        let cameras = rig
            .cameras
            .iter()
            .enumerate()
            .map(|(number, cam)| {
                Ok(CameraProjection {
                    size: (cam.model.width(), cam.model.height()),
                    projector: SphereProjector::new(cam, number, grid)?,
                })
            })
            .collect::<Result<_, NetError>>()?;
        Ok(Self {
            grid: *grid,
            hypotheses: *hypotheses,
            cameras,
        })
    }

    /// The output grid.
    pub fn grid(&self) -> &EquirectGrid {
        &self.grid
    }

    /// Number of cameras.
    pub fn num_cameras(&self) -> usize {
        self.cameras.len()
    }

    /// The hypotheses whose fractional indices the grids read.
    pub fn hypotheses(&self) -> &InvDepthHypotheses {
        &self.hypotheses
    }

    /// The image size `(width, height)` of camera `camera`.
    ///
    /// # Panics
    /// For a camera the rig does not have.
    pub fn image_size(&self, camera: usize) -> (u32, u32) {
        self.cameras[camera].size
    }

    /// The fisheye pixel `(col, row)` where camera `camera` sees grid pixel `pixel`
    /// (row-major) at inverse depth `inv_depth` (1/m); `None` outside its field of view.
    ///
    /// # Panics
    /// For a camera the rig does not have.
    pub fn project(&self, camera: usize, pixel: usize, inv_depth: f32) -> Option<(f32, f32)> {
        self.cameras[camera].projector.project(pixel, inv_depth)
    }

    /// One sweep grid per camera for per-pixel hypotheses: `index` holds `K` planes of
    /// fractional hypothesis indices (`N` units), `[K, rows, cols]` row-major; the grids have
    /// `K` "spheres", one per plane.
    ///
    /// # Errors
    /// [`NetError::Shape`] when `index` is not `K` planes of the grid.
    pub fn grids(&self, index: &[f32], k: usize) -> Result<Vec<SweepGrid>, NetError> {
        self.grids_window(index, k, 0..self.grid.width)
    }

    /// [`PixelSampler::grids`] for the columns `cols` of the grid only: `index` is
    /// `[K, rows, cols.len()]` and so are the grids (training on a window of longitudes).
    ///
    /// # Errors
    /// [`NetError::Shape`] when `cols` leaves the grid or `index` is not `K` planes of the
    /// window.
    pub fn grids_window(
        &self,
        index: &[f32],
        k: usize,
        cols: Range<usize>,
    ) -> Result<Vec<SweepGrid>, NetError> {
        let (rows, width) = (self.grid.height, cols.len());
        if cols.end > self.grid.width || cols.is_empty() {
            return Err(NetError::Shape {
                what: "column window of the grid".into(),
                expected: vec![self.grid.width],
                actual: vec![cols.start, cols.end],
            });
        }
        let plane = rows * width;
        if index.len() != k * plane {
            return Err(NetError::Shape {
                what: "per-pixel hypothesis indices".into(),
                expected: vec![k, rows, width],
                actual: vec![index.len()],
            });
        }
        let step = self.hypotheses.step();
        let min = self.hypotheses.min_inv_depth();
        self.cameras
            .iter()
            .map(|cam| {
                let mut coords = vec![0f32; 2 * index.len()];
                coords
                    .par_chunks_mut(2 * plane)
                    .zip(index.par_chunks(plane))
                    .for_each(|(out, plane_index)| {
                        for (i, (dst, &n)) in out.chunks_exact_mut(2).zip(plane_index).enumerate() {
                            let pixel = (i / width) * self.grid.width + cols.start + i % width;
                            let inv_depth = (min + f64::from(n) * step) as f32;
                            let px = cam.projector.project(pixel, inv_depth);
                            let px = px.map(|(col, row)| (f64::from(col), f64::from(row)));
                            dst.copy_from_slice(&normalized_pixel(px, cam.size));
                        }
                    });
                SweepGrid::new(k, rows, width, coords)
            })
            .collect()
    }

    /// One sweep grid per camera for spheres shared by every pixel at the fractional
    /// hypothesis indices `spheres`.
    ///
    /// # Errors
    /// [`NetError::Shape`] never for consistent inputs (see [`PixelSampler::grids`]).
    pub fn sphere_grids(&self, spheres: &[f64]) -> Result<Vec<SweepGrid>, NetError> {
        let plane = self.grid.len();
        let index: Vec<f32> = spheres
            .iter()
            .flat_map(|&n| std::iter::repeat_n(n as f32, plane))
            .collect();
        self.grids(&index, spheres.len())
    }
}

/// Window sums of a `h x w` map over `(2 r + 1)^2` windows: rows beyond the top and bottom
/// are not there (clipped), columns wrap around (longitude is a ring). `f32` for the cascade's photometric
/// cue, `f64` for the learnt pick's ZNCC.
pub(crate) fn box_sum<T>(map: &[T], h: usize, w: usize, r: usize) -> Vec<T>
where
    T: Copy + Default + std::ops::AddAssign,
{
    let mut vertical = vec![T::default(); h * w];
    for y in 0..h {
        let dst = &mut vertical[y * w..(y + 1) * w];
        for src in y.saturating_sub(r)..(y + r + 1).min(h) {
            for (d, &s) in dst.iter_mut().zip(&map[src * w..(src + 1) * w]) {
                *d += s;
            }
        }
    }
    // Along each row, through a copy with `r` columns of the other end on each side, one
    // offset of the window at a time over the whole row (vectorised): every sum still adds
    // its window's values from left to right, as modulo indexing would.
    let mut out = vec![T::default(); h * w];
    let mut ring = vec![T::default(); w + 2 * r];
    for (row, dst) in vertical.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
        if w >= r {
            ring[..r].copy_from_slice(&row[w - r..]);
            ring[r..r + w].copy_from_slice(row);
            ring[r + w..].copy_from_slice(&row[..r]);
        } else {
            // A window wider than the row (a narrow training window) wraps more than once.
            for (j, v) in ring.iter_mut().enumerate() {
                *v = row[(j + w * r - r) % w];
            }
        }
        dst.copy_from_slice(&ring[..w]);
        for offset in 1..=2 * r {
            for (d, &s) in dst.iter_mut().zip(&ring[offset..offset + w]) {
                *d += s;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_sums_clip_rows_and_wrap_columns() {
        let (h, w) = (3, 5);
        let map: Vec<f32> = (0..h * w).map(|i| i as f32).collect();
        let sums = box_sum(&map, h, w, 1);
        // Row 0, column 0: rows 0-1, columns 4, 0, 1.
        let expected = [4.0, 0.0, 1.0, 9.0, 5.0, 6.0].iter().sum::<f32>();
        assert_eq!(sums[0], expected);
        // Row 1, column 2: rows 0-2, columns 1-3.
        let expected: f32 = (0..3)
            .flat_map(|y| (1..4).map(move |x| (y * w + x) as f32))
            .sum();
        assert_eq!(sums[w + 2], expected);
    }

    #[test]
    fn box_sums_add_each_window_left_to_right_as_modulo_indexing_does() {
        // The reading the vectorised sums replaced: bit for bit, narrow rows included (a
        // training window of one column wraps its window several times).
        let naive = |map: &[f32], h: usize, w: usize, r: usize| -> Vec<f32> {
            let mut out = vec![0f32; h * w];
            for y in 0..h {
                for x in 0..w {
                    let mut column = [0f32; 16];
                    for (j, c) in column.iter_mut().enumerate().take(2 * r + 1) {
                        let xx = (x + w * r + j - r) % w;
                        for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                            *c += map[yy * w + xx];
                        }
                    }
                    out[y * w + x] = column[..2 * r + 1].iter().sum();
                }
            }
            out
        };
        for (h, w, r) in [(7, 13, 2), (5, 1, 2), (4, 2, 2), (6, 3, 1), (9, 40, 3)] {
            let map: Vec<f32> = (0..h * w)
                .map(|i| ((i * 7919 + 13) % 101) as f32 * 0.173 - 5.0)
                .collect();
            let fast = box_sum(&map, h, w, r);
            let slow = naive(&map, h, w, r);
            assert!(
                fast.iter()
                    .zip(&slow)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{h}x{w} r {r}: {fast:?} against {slow:?}"
            );
        }
    }
}
