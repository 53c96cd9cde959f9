//! A camera image prepared for matching: normalised gray values and where a
//! bilinear sample is trustworthy.

use omnimvs_camera::ValidityMask;
use omnimvs_data::image_io::normalize_for_network;
use omnimvs_sweep::GrayImage;

use crate::StereoError;

/// One camera's normalised image (zero mean, unit variance over its valid
/// pixels, as the paper feeds gray images to every method) and, for each
/// pixel `(x, y)`, whether the 2x2 block `(x..=x+1, y..=y+1)` used by a
/// bilinear sample is entirely valid.
#[derive(Debug, Clone)]
pub struct CameraView {
    pub width: usize,
    pub height: usize,
    pub image: Vec<f32>,
    /// Row-major; `true` when a sample with `floor(col) = x`, `floor(row) = y`
    /// touches only valid pixels.
    pub tap_valid: Vec<bool>,
}

impl CameraView {
    /// Prepares camera `camera_number` (1-based, for messages).
    ///
    /// # Errors
    /// [`StereoError::SizeMismatch`] when the mask size differs from the
    /// image's.
    pub fn new(
        image: &GrayImage,
        mask: Option<&ValidityMask>,
        camera_number: usize,
    ) -> Result<Self, StereoError> {
        let (w, h) = (image.width, image.height);
        if let Some(m) = mask
            && (m.width as usize != w || m.height as usize != h)
        {
            return Err(StereoError::SizeMismatch {
                camera: camera_number,
                what: "validity mask",
                found_w: m.width as usize,
                found_h: m.height as usize,
                want_w: w,
                want_h: h,
            });
        }
        let normalised = normalize_for_network(image, mask)?;
        let ok = |x: usize, y: usize| mask.is_none_or(|m| m.valid[y * w + x]);
        let mut tap_valid = vec![false; w * h];
        for y in 0..h.saturating_sub(1) {
            for x in 0..w.saturating_sub(1) {
                tap_valid[y * w + x] = ok(x, y) && ok(x + 1, y) && ok(x, y + 1) && ok(x + 1, y + 1);
            }
        }
        Ok(Self {
            width: w,
            height: h,
            image: normalised.data,
            tap_valid,
        })
    }

    /// Bilinear sample at fractional `(col, row)`; `None` when any of the four
    /// neighbours is outside the image or invalid.
    #[inline]
    pub fn sample(&self, col: f32, row: f32) -> Option<f32> {
        if !(col >= 0.0 && row >= 0.0) {
            return None;
        }
        let x0 = col as usize;
        let y0 = row as usize;
        if x0 + 1 >= self.width || y0 + 1 >= self.height {
            return None;
        }
        let i = y0 * self.width + x0;
        if !self.tap_valid[i] {
            return None;
        }
        let fx = col - x0 as f32;
        let fy = row - y0 as f32;
        let top = self.image[i] + fx * (self.image[i + 1] - self.image[i]);
        let j = i + self.width;
        let bottom = self.image[j] + fx * (self.image[j + 1] - self.image[j]);
        Some(top + fy * (bottom - top))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_bilinearly_and_rejects_invalid_taps() {
        let img = GrayImage {
            width: 3,
            height: 2,
            data: vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0],
        };
        let mask = ValidityMask {
            width: 3,
            height: 2,
            valid: vec![true, true, false, true, true, true],
        };
        let v = CameraView::new(&img, Some(&mask), 1).unwrap();
        // Normalised over the 5 valid pixels; the invalid one is 0.
        assert_eq!(v.sample(0.0, 0.0), Some(v.image[0]));
        assert!(v.sample(1.0, 0.0).is_none(), "the block at x = 1 touches the invalid pixel");
        let mid = v.sample(0.5, 0.5).unwrap();
        let want = (v.image[0] + v.image[1] + v.image[3] + v.image[4]) / 4.0;
        assert!((mid - want).abs() < 1e-6);
        assert!(v.sample(-0.1, 0.0).is_none());
        assert!(v.sample(0.0, 1.0).is_none(), "last row has no block below");
        let bad = ValidityMask {
            width: 2,
            height: 2,
            valid: vec![true; 4],
        };
        assert!(CameraView::new(&img, Some(&bad), 2).is_err());
    }
}
