//! Photometric augmentation: what a real camera does to the light that the renderer does not.
//!
//! The generator renders ideal, noise-free images with one response for every camera. Real
//! rigs differ per camera in exposure, response curve (gamma), vignetting, focus and sensor
//! noise, and the network must match across those differences (the real `itbt_sample` shows
//! all of them). Each camera of a training sample therefore gets its own draw of, in the order
//! light meets them:
//!
//! 1. vignetting: the irradiance falls off as `1 - v r^2` from the image centre (`r` in half
//!    image widths),
//! 2. exposure: a gain, log-uniform, the bright parts clipping at white,
//! 3. optics: a Gaussian blur (with probability one half),
//! 4. the sensor: noise with a read part and a shot part growing with the signal,
//! 5. the response: a gamma curve, log-uniform around 1, then 8-bit quantisation.
//!
//! A pure gain and offset would change nothing: the network's input is normalised per camera
//! over its valid pixels. Clipping, gamma, vignetting, blur and noise do change it.
//!
//! The draws come from a seed per sample (recorded in the epoch's plan), so an epoch is the
//! same whether it runs whole or resumes.

use omnimvs_core::GrayImage;
use serde::{Deserialize, Serialize};

use crate::error::TrainError;
use crate::rng::SplitMix64;

/// Ranges of the photometric augmentation (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhotometricAugment {
    /// Exposure gain range `[low, high]`, drawn log-uniform.
    pub gain: [f64; 2],
    /// Gamma range `[low, high]` (output = input^(1/gamma) on `[0, 1]`), drawn log-uniform.
    pub gamma: [f64; 2],
    /// Largest vignetting strength `v` (the corner at `r = 1` keeps `1 - v`).
    pub max_vignetting: f64,
    /// Largest blur standard deviation, pixels of the camera's image.
    pub max_blur_px: f64,
    /// Largest read-noise standard deviation, gray levels (of 255).
    pub max_read_noise: f64,
    /// Largest shot-noise standard deviation at white, gray levels (of 255).
    pub max_shot_noise: f64,
}

impl Default for PhotometricAugment {
    fn default() -> Self {
        Self {
            gain: [0.6, 1.6],
            gamma: [0.7, 1.4],
            max_vignetting: 0.5,
            max_blur_px: 1.2,
            max_read_noise: 2.0,
            max_shot_noise: 4.0,
        }
    }
}

/// One camera's draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPhotometry {
    /// Vignetting strength.
    pub vignetting: f64,
    /// Exposure gain.
    pub gain: f64,
    /// Blur standard deviation, pixels (0: none).
    pub blur_px: f64,
    /// Read-noise standard deviation, gray levels.
    pub read_noise: f64,
    /// Shot-noise standard deviation at white, gray levels.
    pub shot_noise: f64,
    /// Gamma of the response.
    pub gamma: f64,
}

impl CameraPhotometry {
    /// The camera that changes nothing but the 8-bit quantisation.
    pub const IDENTITY: Self = Self {
        vignetting: 0.0,
        gain: 1.0,
        blur_px: 0.0,
        read_noise: 0.0,
        shot_noise: 0.0,
        gamma: 1.0,
    };
}

impl PhotometricAugment {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`TrainError::InvalidConfig`] naming the field.
    pub fn validate(&self) -> Result<(), TrainError> {
        let range = |field: &'static str, [low, high]: [f64; 2]| {
            if low > 0.0 && low <= high && high.is_finite() {
                Ok(())
            } else {
                Err(TrainError::InvalidConfig {
                    field,
                    message: format!("must be 0 < low <= high, got [{low}, {high}]"),
                })
            }
        };
        range("photometric.gain", self.gain)?;
        range("photometric.gamma", self.gamma)?;
        let non_negative = |field: &'static str, value: f64, max: f64| {
            if (0.0..=max).contains(&value) {
                Ok(())
            } else {
                Err(TrainError::InvalidConfig {
                    field,
                    message: format!("must be in [0, {max}], got {value}"),
                })
            }
        };
        non_negative("photometric.max_vignetting", self.max_vignetting, 0.9)?;
        non_negative("photometric.max_blur_px", self.max_blur_px, 5.0)?;
        non_negative("photometric.max_read_noise", self.max_read_noise, 50.0)?;
        non_negative("photometric.max_shot_noise", self.max_shot_noise, 50.0)
    }

    /// The draws of `cameras` cameras for the sample seeded `seed`.
    pub fn draw(&self, seed: u64, cameras: usize) -> Vec<CameraPhotometry> {
        let mut rng = SplitMix64::new(seed ^ 0x7068_6f74_6f6d);
        let log_uniform = |rng: &mut SplitMix64, [low, high]: [f64; 2]| {
            (low.ln() + rng.next_f64() * (high.ln() - low.ln())).exp()
        };
        (0..cameras)
            .map(|_| {
                let vignetting = rng.next_f64() * self.max_vignetting;
                let gain = log_uniform(&mut rng, self.gain);
                let blur = rng.next_f64();
                let blur_px = if blur < 0.5 {
                    0.0
                } else {
                    (blur - 0.5) * 2.0 * self.max_blur_px
                };
                let read_noise = rng.next_f64() * self.max_read_noise;
                let shot_noise = rng.next_f64() * self.max_shot_noise;
                let gamma = log_uniform(&mut rng, self.gamma);
                CameraPhotometry {
                    vignetting,
                    gain,
                    blur_px,
                    read_noise,
                    shot_noise,
                    gamma,
                }
            })
            .collect()
    }

    /// Applies the draws of sample `seed` to the gray images (`[0, 255]`) of every camera.
    pub fn apply(&self, images: &mut [GrayImage], seed: u64) {
        let draws = self.draw(seed, images.len());
        for (camera, (image, draw)) in images.iter_mut().zip(&draws).enumerate() {
            let noise_seed = seed ^ (0x6e6f_6973_6500 + camera as u64);
            apply_camera(image, draw, noise_seed);
        }
    }
}

/// Applies one camera's draw to `image` (gray levels in `[0, 255]`), noise from `noise_seed`.
pub fn apply_camera(image: &mut GrayImage, draw: &CameraPhotometry, noise_seed: u64) {
    let (width, height) = (image.width, image.height);
    if width == 0 || height == 0 {
        return;
    }
    let (cx, cy) = ((width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0);
    let radius = width.max(height) as f64 / 2.0;
    // Irradiance in [0, 1], vignetted and exposed.
    let mut light: Vec<f32> = Vec::with_capacity(width * height);
    for y in 0..height {
        let dy = (y as f64 - cy) / radius;
        for x in 0..width {
            let dx = (x as f64 - cx) / radius;
            let falloff = (1.0 - draw.vignetting * (dx * dx + dy * dy)).max(0.05);
            let value = f64::from(image.data[y * width + x]) / 255.0;
            light.push((value * falloff * draw.gain) as f32);
        }
    }
    if draw.blur_px > 0.05 {
        light = gaussian_blur(&light, width, height, draw.blur_px);
    }
    let mut rng = SplitMix64::new(noise_seed);
    let read = draw.read_noise / 255.0;
    let shot = draw.shot_noise / 255.0;
    let inverse_gamma = 1.0 / draw.gamma;
    let noisy = read > 0.0 || shot > 0.0;
    for (out, &value) in image.data.iter_mut().zip(&light) {
        let mut v = f64::from(value).clamp(0.0, 1.0);
        if noisy {
            // Variance read^2 + shot^2 * signal: shot noise grows with the light.
            let sigma = (read * read + shot * shot * v).sqrt();
            v = (v + sigma * standard_normal(&mut rng)).clamp(0.0, 1.0);
        }
        *out = (v.powf(inverse_gamma) * 255.0).round() as f32;
    }
}

/// One standard normal draw (Box-Muller).
fn standard_normal(rng: &mut SplitMix64) -> f64 {
    let u1 = rng.next_f64().max(1e-12);
    let u2 = rng.next_f64();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Separable Gaussian blur with clamped borders.
fn gaussian_blur(data: &[f32], width: usize, height: usize, sigma: f64) -> Vec<f32> {
    let half = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-half..=half)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let total: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / total).collect();
    let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
    let mut rows = vec![0f32; data.len()];
    for y in 0..height {
        let row = &data[y * width..(y + 1) * width];
        for x in 0..width {
            rows[y * width + x] = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| w * row[clamp(x as isize + k as isize - half, width)])
                .sum();
        }
    }
    let mut out = vec![0f32; data.len()];
    for y in 0..height {
        for x in 0..width {
            out[y * width + x] = kernel
                .iter()
                .enumerate()
                .map(|(k, w)| w * rows[clamp(y as isize + k as isize - half, height) * width + x])
                .sum();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(width: usize, height: usize) -> GrayImage {
        GrayImage {
            width,
            height,
            data: (0..width * height)
                .map(|i| ((i * 37) % 256) as f32)
                .collect(),
        }
    }

    #[test]
    fn identity_keeps_8_bit_images() {
        let mut image = ramp(40, 30);
        let before = image.clone();
        apply_camera(&mut image, &CameraPhotometry::IDENTITY, 1);
        assert_eq!(image, before);
    }

    #[test]
    fn draws_are_seeded_within_their_ranges_and_differ_per_camera() {
        let augment = PhotometricAugment::default();
        let a = augment.draw(5, 4);
        assert_eq!(a, augment.draw(5, 4));
        assert_ne!(a, augment.draw(6, 4));
        assert_ne!(a[0], a[1]);
        for seed in 0..200 {
            for d in augment.draw(seed, 4) {
                assert!((0.6..=1.6).contains(&d.gain), "{d:?}");
                assert!((0.7..=1.4).contains(&d.gamma), "{d:?}");
                assert!((0.0..=0.5).contains(&d.vignetting), "{d:?}");
                assert!((0.0..=1.2).contains(&d.blur_px), "{d:?}");
            }
        }
        // About half the cameras are blurred.
        let blurred = (0..200)
            .flat_map(|s| augment.draw(s, 4))
            .filter(|d| d.blur_px > 0.0)
            .count();
        assert!((300..500).contains(&blurred), "{blurred} of 800 blurred");
    }

    #[test]
    fn each_effect_does_what_it_says() {
        let flat = GrayImage {
            width: 64,
            height: 64,
            data: vec![128.0; 64 * 64],
        };
        let mean = |img: &GrayImage| img.data.iter().sum::<f32>() / img.data.len() as f32;
        let at = |img: &GrayImage, x: usize, y: usize| img.data[y * img.width + x];

        // Vignetting darkens the corners, not the centre.
        let mut v = flat.clone();
        let draw = CameraPhotometry {
            vignetting: 0.5,
            ..CameraPhotometry::IDENTITY
        };
        apply_camera(&mut v, &draw, 0);
        assert!((at(&v, 32, 32) - 128.0).abs() <= 1.0);
        assert!(at(&v, 0, 0) < 80.0, "corner {}", at(&v, 0, 0));

        // Gain clips at white.
        let mut g = flat.clone();
        let draw = CameraPhotometry {
            gain: 2.5,
            ..CameraPhotometry::IDENTITY
        };
        apply_camera(&mut g, &draw, 0);
        assert!(g.data.iter().all(|&p| p == 255.0));

        // Gamma above 1 brightens the mid tones.
        let mut c = flat.clone();
        let draw = CameraPhotometry {
            gamma: 1.4,
            ..CameraPhotometry::IDENTITY
        };
        apply_camera(&mut c, &draw, 0);
        assert!(mean(&c) > 150.0, "{}", mean(&c));

        // Noise keeps the mean and adds the variance asked for.
        let mut n = flat.clone();
        let draw = CameraPhotometry {
            read_noise: 3.0,
            ..CameraPhotometry::IDENTITY
        };
        apply_camera(&mut n, &draw, 9);
        let m = mean(&n);
        let sd = (n.data.iter().map(|p| (p - m).powi(2)).sum::<f32>() / n.data.len() as f32).sqrt();
        assert!((m - 128.0).abs() < 0.3, "mean {m}");
        assert!((2.6..3.4).contains(&sd), "sd {sd}");

        // Blur keeps a flat image and smooths an edge.
        let mut edge = GrayImage {
            width: 32,
            height: 8,
            data: (0..256)
                .map(|i| if i % 32 < 16 { 0.0 } else { 200.0 })
                .collect(),
        };
        let draw = CameraPhotometry {
            blur_px: 1.0,
            ..CameraPhotometry::IDENTITY
        };
        let mut b = flat.clone();
        apply_camera(&mut b, &draw, 0);
        assert_eq!(b, flat);
        apply_camera(&mut edge, &draw, 0);
        let row = &edge.data[4 * 32..5 * 32];
        assert!(row[15] > 10.0 && row[16] < 190.0, "{row:?}");
        assert_eq!((row[0], row[31]), (0.0, 200.0));
    }

    #[test]
    fn invalid_ranges_are_refused_by_name() {
        let bad = PhotometricAugment {
            gamma: [1.2, 0.8],
            ..PhotometricAugment::default()
        };
        let message = bad.validate().map_err(|e| e.to_string()).unwrap_err();
        assert!(message.contains("photometric.gamma"), "{message}");
        assert!(PhotometricAugment::default().validate().is_ok());
    }
}
