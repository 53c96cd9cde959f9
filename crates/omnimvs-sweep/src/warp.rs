//! Bilinear warping with `grid_sample(align_corners=True, padding=zeros)`
//! semantics: a sample position `(col, row)` in pixels blends the four
//! neighbouring pixels, and neighbours outside the image contribute zero.

use rayon::prelude::*;

use crate::{LookupTable, SweepError};

/// A single-channel f32 image, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct GrayImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl GrayImage {
    /// An image of zeros.
    pub fn zeros(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }

    /// Bilinear sample at a fractional pixel position, zero outside.
    pub fn sample(&self, col: f64, row: f64) -> f32 {
        sample_bilinear(&self.data, self.width, self.height, col, row)
    }
}

/// The four neighbours of a sample position and their bilinear weights; a
/// neighbour outside the source image has weight 0 (and index 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BilinearTap {
    /// Row-major indices into the source plane: top-left, top-right,
    /// bottom-left, bottom-right.
    pub index: [u32; 4],
    pub weight: [f32; 4],
}

impl BilinearTap {
    /// The tap of a fractional source pixel `(col, row)` in an image of
    /// `width x height`.
    pub fn from_pixel(col: f64, row: f64, width: usize, height: usize) -> Self {
        let mut tap = Self::default();
        if !(col.is_finite() && row.is_finite()) {
            return tap;
        }
        let x0 = col.floor();
        let y0 = row.floor();
        let fx = (col - x0) as f32;
        let fy = (row - y0) as f32;
        let (x0, y0) = (x0 as i64, y0 as i64);
        let corners = [
            (x0, y0, (1.0 - fx) * (1.0 - fy)),
            (x0 + 1, y0, fx * (1.0 - fy)),
            (x0, y0 + 1, (1.0 - fx) * fy),
            (x0 + 1, y0 + 1, fx * fy),
        ];
        for (k, &(x, y, w)) in corners.iter().enumerate() {
            if x >= 0 && y >= 0 && (x as usize) < width && (y as usize) < height {
                tap.index[k] = (y as usize * width + x as usize) as u32;
                tap.weight[k] = w;
            }
        }
        tap
    }

    /// The tap of a position normalised as in the lookup table
    /// (`x = col/(width-1)*2-1`, `y = row/(height-1)*2-1`).
    pub fn from_normalized(x: f32, y: f32, width: usize, height: usize) -> Self {
        let col = (f64::from(x) + 1.0) / 2.0 * (width as f64 - 1.0);
        let row = (f64::from(y) + 1.0) / 2.0 * (height as f64 - 1.0);
        Self::from_pixel(col, row, width, height)
    }

    /// Whether every weight is zero (the sample lies entirely outside).
    pub fn is_empty(&self) -> bool {
        self.weight.iter().all(|&w| w == 0.0)
    }

    /// The blended value from a source plane.
    #[inline]
    pub fn apply(&self, plane: &[f32]) -> f32 {
        let mut acc = 0.0;
        for k in 0..4 {
            acc += self.weight[k] * plane[self.index[k] as usize];
        }
        acc
    }
}

/// Bilinear sample of a row-major plane at fractional `(col, row)`, zero
/// outside (the align-corners convention: pixel centres at integers).
pub fn sample_bilinear(plane: &[f32], width: usize, height: usize, col: f64, row: f64) -> f32 {
    BilinearTap::from_pixel(col, row, width, height).apply(plane)
}

/// Warps a `channels x height x width` map of camera `cam` onto every sphere
/// of `lut`, writing `[sphere, channel, grid_h, grid_w]` into `out`.
///
/// The map may have any resolution (a feature map at half the image size,
/// say): the table's normalised coordinates are scaled to it.
///
/// # Errors
/// [`SweepError::Mismatch`] when `src` or `out` has the wrong length or `cam`
/// is out of range.
pub fn warp_camera_onto_spheres(
    lut: &LookupTable,
    cam: usize,
    src: &[f32],
    channels: usize,
    width: usize,
    height: usize,
    out: &mut [f32],
) -> Result<(), SweepError> {
    if cam >= lut.num_cameras() {
        return Err(SweepError::mismatch(
            "camera index",
            format!("< {}", lut.num_cameras()),
            cam,
        ));
    }
    if src.len() != channels * width * height {
        return Err(SweepError::mismatch(
            "source map length",
            format!(
                "{channels} x {height} x {width} = {}",
                channels * width * height
            ),
            src.len(),
        ));
    }
    let grid_len = lut.grid.len();
    let want = lut.num_spheres() * channels * grid_len;
    if out.len() != want {
        return Err(SweepError::mismatch("warp output length", want, out.len()));
    }
    let plane_len = width * height;
    out.par_chunks_mut(channels * grid_len)
        .enumerate()
        .for_each(|(sphere, dst)| {
            let lut_plane = lut.plane(cam, sphere);
            for (i, xy) in lut_plane.chunks_exact(2).enumerate() {
                let tap = BilinearTap::from_normalized(xy[0], xy[1], width, height);
                for c in 0..channels {
                    dst[c * grid_len + i] = tap.apply(&src[c * plane_len..(c + 1) * plane_len]);
                }
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_interpolates_and_pads_with_zero() {
        // 2x2 image [[1, 2], [3, 4]].
        let img = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(sample_bilinear(&img, 2, 2, 0.0, 0.0), 1.0);
        assert_eq!(sample_bilinear(&img, 2, 2, 1.0, 1.0), 4.0);
        assert!((sample_bilinear(&img, 2, 2, 0.5, 0.5) - 2.5).abs() < 1e-6);
        // Half a pixel left of the image: half the weight is outside (zero).
        assert!((sample_bilinear(&img, 2, 2, -0.5, 0.0) - 0.5).abs() < 1e-6);
        assert_eq!(sample_bilinear(&img, 2, 2, -1e5, 0.0), 0.0);
        assert_eq!(sample_bilinear(&img, 2, 2, f64::NAN, 0.0), 0.0);
    }

    #[test]
    fn normalized_corners_hit_corner_pixels() {
        let t = BilinearTap::from_normalized(-1.0, -1.0, 800, 768);
        assert_eq!(t.index[0], 0);
        assert!((t.weight[0] - 1.0).abs() < 1e-6);
        let t = BilinearTap::from_normalized(1.0, 1.0, 800, 768);
        assert_eq!(t.index[0], 800 * 768 - 1);
        assert!((t.weight[0] - 1.0).abs() < 1e-4);
    }
}
