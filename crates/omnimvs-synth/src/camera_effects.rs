//! Real-camera effects on the rendered 8-bit images: what makes a real rig
//! differ from an ideal renderer. Per camera and frame, drawn from the
//! dataset seed: exposure and gain, a gamma curve, vignetting, lens blur and
//! sensor noise (read noise plus shot noise). Only the images change; the
//! ground truth is the scene's.
//!
//! The pipeline of one camera, on brightness `x` in `[0, 1]` (the rendered
//! value / 255): Gaussian blur (`blur_px`), then `x * gain * v(theta)` with
//! the vignetting `v(theta) = 1 - vignetting * (theta / theta_max)^2`
//! (`theta` the ray's angle from the optical axis, `theta_max` the largest in
//! the image), then `x^gamma`, then Gaussian noise of variance
//! `read_noise^2 + shot_noise * level` in gray levels, rounded and clamped to
//! 8 bits. Pixels outside the field of view stay 0.

use omnimvs_camera::{Camera, Pixel};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::SynthError;
use crate::rng::Rng;

/// The effects of one camera in one frame (as stored in `scene.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraEffects {
    /// Exposure times gain: multiplies the brightness.
    pub gain: f32,
    /// Exponent of the tone curve, `x^gamma` (1: linear).
    pub gamma: f32,
    /// Brightness lost at the edge of the field of view, `[0, 1)`.
    pub vignetting: f32,
    /// Standard deviation of the Gaussian blur, pixels (0: none).
    pub blur_px: f32,
    /// Standard deviation of the signal-independent noise, gray levels.
    pub read_noise: f32,
    /// Variance of the shot noise per gray level of signal.
    pub shot_noise: f32,
    /// Seed of the noise pattern.
    pub noise_seed: u64,
}

impl CameraEffects {
    /// No effect at all: [`Self::apply`] leaves an image unchanged.
    pub fn identity() -> Self {
        Self {
            gain: 1.0,
            gamma: 1.0,
            vignetting: 0.0,
            blur_px: 0.0,
            read_noise: 0.0,
            shot_noise: 0.0,
            noise_seed: 0,
        }
    }

    /// The effects of every camera of a rig in frame `frame` of the dataset
    /// of `seed`: one exposure bias for the frame (0.7-1.4, on top of
    /// [`auto_expose`]), a gain, gamma, vignetting, blur and noise per
    /// camera. A stream of its own, so the scene of the frame does not
    /// depend on it.
    pub fn draw(seed: u64, frame: u32, num_cameras: usize) -> Vec<Self> {
        let mut rng = Rng::for_frame(seed, "camera-effects", frame);
        let exposure = rng.log_range(0.7, 1.4);
        let read_noise = rng.range(0.5, 2.5);
        (0..num_cameras)
            .map(|_| {
                let mut c = rng.fork();
                Self {
                    gain: (exposure * c.log_range(0.8, 1.25)) as f32,
                    gamma: c.log_range(0.8, 1.25) as f32,
                    vignetting: c.range(0.1, 0.5) as f32,
                    blur_px: c.range(0.2, 0.8) as f32,
                    read_noise: (read_noise * c.range(0.8, 1.25)) as f32,
                    shot_noise: c.range(0.0, 0.1) as f32,
                    noise_seed: c.next_u64(),
                }
            })
            .collect()
    }

    /// Applies the effects to `image` (8-bit gray, `height x width` of
    /// `camera`), in place. Deterministic for any number of threads: each row
    /// draws its noise from its own stream.
    ///
    /// # Errors
    /// [`SynthError::Invalid`] when the image size is not the camera's.
    pub fn apply(&self, camera: &Camera, image: &mut [u8]) -> Result<(), SynthError> {
        let (w, h) = (
            camera.model.width() as usize,
            camera.model.height() as usize,
        );
        if image.len() != w * h {
            return Err(SynthError::invalid(
                format!("image of camera {}", camera.id),
                format!("expected {w}x{h} = {} pixels, found {}", w * h, image.len()),
            ));
        }
        // Angle from the optical axis of every pixel centre; NaN outside
        // the field of view.
        let mut theta = vec![f32::NAN; w * h];
        theta.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
            for (col, t) in line.iter_mut().enumerate() {
                if let Some(r) = camera.model.unproject(Pixel::new(col as f64, row as f64)) {
                    *t = (r.z / r.norm()).clamp(-1.0, 1.0).acos() as f32;
                }
            }
        });
        let theta_max = theta
            .iter()
            .copied()
            .filter(|t| t.is_finite())
            .fold(0.0f32, f32::max)
            .max(1e-6);
        let x: Vec<f32> = image.iter().map(|&v| f32::from(v) / 255.0).collect();
        let x = gaussian_blur(&x, w, h, self.blur_px);
        let (gain, gamma, vig) = (self.gain, self.gamma, self.vignetting);
        let (read_var, shot) = (self.read_noise * self.read_noise, self.shot_noise);
        image.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
            let mut rng = Rng::for_frame(self.noise_seed, "noise-row", row as u32);
            for (col, px) in line.iter_mut().enumerate() {
                let i = row * w + col;
                let t = theta[i];
                if !t.is_finite() {
                    *px = 0;
                    continue;
                }
                let rel = t / theta_max;
                let lin = (x[i] * gain * (1.0 - vig * rel * rel)).clamp(0.0, 1.0);
                let level = 255.0 * lin.powf(gamma);
                let sigma = (read_var + shot * level).sqrt();
                let noisy = level + sigma * gaussian(&mut rng);
                *px = (noisy + 0.5).clamp(0.0, 255.0) as u8;
            }
        });
        Ok(())
    }
}

/// Mean gray level a frame is exposed for by [`auto_expose`].
pub const AUTO_EXPOSURE_LEVEL: f64 = 90.0;

/// Auto-exposure, as a real rig's cameras do it: scales every camera's gain
/// by one factor (within `[0.5, 6]`) that brings the mean of the ideal
/// images' lit pixels (value > 0) to [`AUTO_EXPOSURE_LEVEL`] gray levels, so
/// that a dark scene is amplified (with its quantisation and noise) and a
/// bright one is not washed out. Deterministic: a function of the images.
pub fn auto_expose(effects: &mut [CameraEffects], images: &[Vec<u8>]) {
    let (sum, count) = images
        .iter()
        .flatten()
        .filter(|&&v| v > 0)
        .fold((0u64, 0u64), |(s, n), &v| (s + u64::from(v), n + 1));
    if count == 0 {
        return;
    }
    let mean = sum as f64 / count as f64;
    let factor = (AUTO_EXPOSURE_LEVEL / mean).clamp(0.5, 6.0) as f32;
    for e in effects {
        e.gain *= factor;
    }
}

/// Applies `effects[k]` to `images[k]` of camera `k` of `cameras`.
///
/// # Errors
/// [`SynthError::Invalid`] when the counts or an image size do not match.
pub fn apply_all(
    effects: &[CameraEffects],
    cameras: &[Camera],
    images: &mut [Vec<u8>],
) -> Result<(), SynthError> {
    if effects.len() != cameras.len() || images.len() != cameras.len() {
        return Err(SynthError::invalid(
            "camera_effects",
            format!(
                "expected one per camera ({}), found {} effects and {} images",
                cameras.len(),
                effects.len(),
                images.len()
            ),
        ));
    }
    for ((e, c), img) in effects.iter().zip(cameras).zip(images.iter_mut()) {
        e.apply(c, img)?;
    }
    Ok(())
}

/// A standard normal deviate (Box-Muller, one of the pair).
fn gaussian(rng: &mut Rng) -> f32 {
    let u1 = rng.f64().max(1e-300);
    let u2 = rng.f64();
    ((-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()) as f32
}

/// Separable Gaussian blur of a `w x h` image, edges clamped; `sigma <= 0`
/// returns the image unchanged.
fn gaussian_blur(x: &[f32], w: usize, h: usize, sigma: f32) -> Vec<f32> {
    if sigma <= 0.0 || w == 0 || h == 0 {
        return x.to_vec();
    }
    let r = (3.0 * sigma).ceil().max(1.0) as usize;
    let mut k: Vec<f32> = (0..=2 * r)
        .map(|i| {
            let d = i as f32 - r as f32;
            (-d * d / (2.0 * sigma * sigma)).exp()
        })
        .collect();
    let sum: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    let mut tmp = vec![0f32; w * h];
    tmp.par_chunks_mut(w).enumerate().for_each(|(row, out)| {
        let src = &x[row * w..(row + 1) * w];
        for (col, o) in out.iter_mut().enumerate() {
            *o = k
                .iter()
                .enumerate()
                .map(|(j, kv)| kv * src[(col + j).saturating_sub(r).min(w - 1)])
                .sum();
        }
    });
    let mut out = vec![0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        for (col, o) in line.iter_mut().enumerate() {
            *o = k
                .iter()
                .enumerate()
                .map(|(j, kv)| kv * tmp[(row + j).saturating_sub(r).min(h - 1) * w + col])
                .sum();
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::{preset_rig, resize_rig};

    #[test]
    fn identity_leaves_the_image_and_blur_keeps_the_mean() {
        let rig = resize_rig(&preset_rig().unwrap().rig, 48, 50).unwrap();
        let cam = &rig.cameras[0];
        let (w, h) = (50, 48);
        let mut img: Vec<u8> = (0..w * h)
            .map(|i| {
                let inside = cam
                    .model
                    .unproject(Pixel::new((i % w) as f64, (i / w) as f64))
                    .is_some();
                if inside { (i * 7 % 251) as u8 } else { 0 }
            })
            .collect();
        let before = img.clone();
        CameraEffects::identity().apply(cam, &mut img).unwrap();
        assert_eq!(img, before);

        let flat = vec![0.5f32; 30 * 20];
        let b = gaussian_blur(&flat, 30, 20, 0.7);
        assert!(b.iter().all(|v| (v - 0.5).abs() < 1e-5));
        let mut wrong = vec![0u8; 10];
        assert!(CameraEffects::identity().apply(cam, &mut wrong).is_err());
    }

    #[test]
    fn auto_exposure_brings_a_dark_frame_up_within_limits() {
        let mut e = vec![CameraEffects::identity(); 2];
        auto_expose(&mut e, &[vec![0, 30, 30], vec![30, 0, 30]]);
        assert!((e[0].gain - 3.0).abs() < 1e-6 && e[0].gain == e[1].gain);
        let mut e = vec![CameraEffects::identity()];
        auto_expose(&mut e, &[vec![1, 1, 0]]);
        assert_eq!(e[0].gain, 6.0);
        let mut e = vec![CameraEffects::identity()];
        auto_expose(&mut e, &[vec![0, 0]]);
        assert_eq!(e[0].gain, 1.0);
    }

    #[test]
    fn draws_are_deterministic_in_range_and_differ_between_cameras() {
        let a = CameraEffects::draw(9, 3, 4);
        assert_eq!(a, CameraEffects::draw(9, 3, 4));
        assert_ne!(a, CameraEffects::draw(9, 4, 4));
        assert_ne!(a[0].gain, a[1].gain);
        for e in &a {
            assert!((0.5..2.0).contains(&e.gain), "{e:?}");
            assert!((0.8..1.25).contains(&e.gamma), "{e:?}");
            assert!((0.0..0.5).contains(&e.vignetting), "{e:?}");
        }
    }
}
