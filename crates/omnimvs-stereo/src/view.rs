//! A camera image prepared for matching: compact texels that carry both the
//! gray value and whether a bilinear sample there is trustworthy.

use omnimvs_camera::ValidityMask;
use omnimvs_sweep::GrayImage;

use crate::StereoError;

/// Fixed-point steps per gray level in a texel.
const TEXEL_SCALE: f32 = 128.0;

/// One camera's image for matching. Each texel is a `u16`: bit 0 says
/// whether the 2x2 block `(x..=x+1, y..=y+1)` used by a bilinear sample with
/// top-left corner `(x, y)` is entirely valid, bits 1-15 hold the gray value
/// (clamped to `[0, 255]`) in 1/128 steps. Two bytes per pixel keep all
/// four images of a rig in cache, which is what bounds the warping speed.
///
/// Samples come out normalised to zero mean and unit variance over the
/// camera's valid pixels (the paper feeds normalised gray images to every
/// method; ZNCC itself does not depend on it, only the variance floor
/// [`crate::ZNCC_VARIANCE_EPS`] does).
#[derive(Debug, Clone)]
pub struct CameraView {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<u16>,
    /// Mean gray value over the valid pixels.
    pub mean: f32,
    /// `1 / std` over the valid pixels (0 for a constant image).
    pub inv_std: f32,
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
        let ok = |i: usize| mask.is_none_or(|m| m.valid[i]);
        let (mut sum, mut sum_sq, mut n) = (0f64, 0f64, 0usize);
        for (i, &v) in image.data.iter().enumerate() {
            if ok(i) {
                let v = f64::from(v.clamp(0.0, 255.0));
                sum += v;
                sum_sq += v * v;
                n += 1;
            }
        }
        let mean = if n > 0 { sum / n as f64 } else { 0.0 };
        let var = if n > 0 {
            sum_sq / n as f64 - mean * mean
        } else {
            0.0
        };
        let inv_std = if var > 1e-9 { 1.0 / var.sqrt() } else { 0.0 };
        let mut texels: Vec<u16> = image
            .data
            .iter()
            .map(|&v| ((v.clamp(0.0, 255.0) * TEXEL_SCALE).round() as u16) << 1)
            .collect();
        for y in 0..h.saturating_sub(1) {
            for x in 0..w.saturating_sub(1) {
                let i = y * w + x;
                if ok(i) && ok(i + 1) && ok(i + w) && ok(i + w + 1) {
                    texels[i] |= 1;
                }
            }
        }
        Ok(Self {
            width: w,
            height: h,
            texels,
            mean: mean as f32,
            inv_std: inv_std as f32,
        })
    }

    /// Bilinear sample at fractional `(col, row)`, normalised; `None` when
    /// any of the four neighbours is outside the image or invalid.
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
        let t00 = self.texels[i];
        if t00 & 1 == 0 {
            return None;
        }
        let j = i + self.width;
        let v = |t: u16| f32::from(t >> 1);
        let (a, b, c, d) = (
            v(t00),
            v(self.texels[i + 1]),
            v(self.texels[j]),
            v(self.texels[j + 1]),
        );
        let fx = col - x0 as f32;
        let fy = row - y0 as f32;
        let top = a + fx * (b - a);
        let bottom = c + fx * (d - c);
        let gray = (top + fy * (bottom - top)) * (1.0 / TEXEL_SCALE);
        Some((gray - self.mean) * self.inv_std)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_bilinearly_normalised_and_rejects_invalid_taps() {
        let img = GrayImage {
            width: 3,
            height: 2,
            data: vec![0.0, 10.0, 200.0, 30.0, 40.0, 50.0],
        };
        let mask = ValidityMask {
            width: 3,
            height: 2,
            valid: vec![true, true, false, true, true, true],
        };
        let v = CameraView::new(&img, Some(&mask), 1).unwrap();
        // Statistics over the 5 valid pixels: mean 26, variance 344.
        assert!((v.mean - 26.0).abs() < 1e-4);
        assert!((v.inv_std - 1.0 / 344f32.sqrt()).abs() < 1e-6);
        let norm = |g: f32| (g - 26.0) / 344f32.sqrt();
        assert!((v.sample(0.0, 0.0).unwrap() - norm(0.0)).abs() < 1e-5);
        assert!(
            v.sample(1.0, 0.0).is_none(),
            "the block at x = 1 touches the invalid pixel"
        );
        let mid = v.sample(0.5, 0.5).unwrap();
        assert!((mid - norm(20.0)).abs() < 1e-4);
        let q = v.sample(0.25, 0.0).unwrap();
        assert!((q - norm(2.5)).abs() < 1e-4);
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
