//! Learned matching costs: per-camera feature maps from a network, compared across
//! the cameras that see a sphere point.
//!
//! A [`FeatureExtractor`] (implemented by the MC-CNN-style network of `omnimvs-net`) turns each
//! camera's gray image into a dense feature map, computed once per frame on the fisheye image
//! (a siamese tower: the same weights for every camera). For every output pixel and
//! hypothesis, each camera's map is sampled bilinearly where the pixel's ray meets the sphere
//! (the same [`SphereProjector`] as ZNCC), and the cost is `(1 - cos) / 2` averaged over the
//! pairs of cameras that both see the point, [`NO_PAIR_COST`] where fewer than two do: the
//! same `[0, 1]` scale as the ZNCC cost, so SGM and its penalties apply unchanged.

use std::fmt::Debug;
use std::time::{Duration, Instant};

use omnimvs_core::GrayImage;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use rayon::prelude::*;

use crate::cost::{NO_PAIR_COST, camera_pairs, fill_odd_hypotheses, finished_volume};
use crate::params::{SweepStep, cost_units};
use omnimvs_core::interp::sample_channels_inside;

use crate::{CameraView, CostTimings, CostVolume, StereoError};
use omnimvs_sweep::SphereProjector;

/// One camera's dense features, `data[(y * width + x) * channels + c]`, on a grid that is the
/// camera image scaled by `1 / stride` (pixel `j` of the map covers image pixels
/// `stride * j .. stride * (j + 1)`).
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureMap {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    /// Image pixels per map pixel (1: full resolution).
    pub stride: usize,
    pub data: Vec<f32>,
}

impl FeatureMap {
    /// Bilinear sample of all channels at image position `(col, row)` (pixel centres at
    /// integers) into `out`; false outside the map.
    #[inline]
    pub fn sample_into(&self, col: f32, row: f32, out: &mut [f32]) -> bool {
        let s = self.stride as f32;
        // Centre of map pixel j is image position s * j + (s - 1) / 2.
        let x = (col - (s - 1.0) * 0.5) / s;
        let y = (row - (s - 1.0) * 0.5) / s;
        sample_channels_inside(
            &self.data,
            [self.width, self.height, self.channels],
            x,
            y,
            out,
        )
    }
}

/// A network that turns each camera's gray image into a [`FeatureMap`] (the siamese half of
/// an MC-CNN-style matching cost).
pub trait FeatureExtractor: Debug + Send + Sync {
    /// The method's name in reports (`MC-CNN+SGM`).
    fn method_name(&self) -> &str;

    /// The feature maps of one frame's images, one per camera, every one with the same
    /// number of channels.
    ///
    /// # Errors
    /// The network's own error, as a message.
    fn features(&self, images: &[GrayImage]) -> Result<Vec<FeatureMap>, StereoError>;
}

/// The cost volume of a frame from its feature maps: `(1 - cos) / 2` averaged over the camera
/// pairs that both see the point (validity from the camera views: masks and image borders).
///
/// # Errors
/// [`StereoError::Volume`] for maps of different channel counts or a camera count that
/// differs from the projectors'.
pub fn feature_cost_volume(
    grid: &EquirectGrid,
    projectors: &[SphereProjector],
    views: &[CameraView],
    maps: &[FeatureMap],
    hyps: &InvDepthHypotheses,
    sweep: SweepStep,
) -> Result<(CostVolume, CostTimings), StereoError> {
    let ncam = maps.len();
    if ncam != projectors.len() || ncam != views.len() {
        return Err(StereoError::CountMismatch {
            what: "feature maps",
            expected: projectors.len(),
            found: ncam,
        });
    }
    let ch = maps[0].channels;
    if maps
        .iter()
        .any(|m| m.channels != ch || m.data.len() != m.width * m.height * ch)
    {
        return Err(StereoError::Volume(
            "feature maps: expected the same channel count in every camera".into(),
        ));
    }
    let (w, h, nd) = (grid.width, grid.height, hyps.count);
    let step = sweep.stride();
    let pairs = camera_pairs(ncam);
    let inv_depths: Vec<f32> = (0..nd).map(|n| hyps.inv_depth(n as f64) as f32).collect();
    let start = Instant::now();
    let mut data = vec![0u16; w * h * nd];
    data.par_chunks_mut(w * nd).enumerate().for_each_init(
        || {
            (
                vec![0f32; w],
                vec![0f32; w],
                vec![0f32; w],
                vec![0f32; ncam * w * ch],
                vec![false; ncam * w],
            )
        },
        |(pc, pr, tp, feat, seen), (row, out)| {
            for n in (0..nd).step_by(step) {
                for cam in 0..ncam {
                    projectors[cam].project_run(row * w, inv_depths[n], pc, pr, tp);
                    for x in 0..w {
                        let k = cam * w + x;
                        let f = &mut feat[k * ch..(k + 1) * ch];
                        seen[k] = views[cam].sample(pc[x], pr[x]).is_some()
                            && maps[cam].sample_into(pc[x], pr[x], f);
                        if seen[k] {
                            let norm = f.iter().map(|v| v * v).sum::<f32>().sqrt();
                            let inv = if norm > 1e-12 { 1.0 / norm } else { 0.0 };
                            f.iter_mut().for_each(|v| *v *= inv);
                        }
                    }
                }
                for x in 0..w {
                    let (mut sum, mut count) = (0f32, 0u32);
                    for &(a, b) in &pairs {
                        let (ka, kb) = (a * w + x, b * w + x);
                        if seen[ka] && seen[kb] {
                            let fa = &feat[ka * ch..(ka + 1) * ch];
                            let fb = &feat[kb * ch..(kb + 1) * ch];
                            let cos: f32 = fa.iter().zip(fb).map(|(p, q)| p * q).sum();
                            sum += 0.5 * (1.0 - cos.clamp(-1.0, 1.0));
                            count += 1;
                        }
                    }
                    let cost = if count > 0 {
                        sum / count as f32
                    } else {
                        NO_PAIR_COST
                    };
                    out[x * nd + n] = cost_units(cost);
                }
            }
            if step == 2 {
                out.chunks_exact_mut(nd).for_each(fill_odd_hypotheses);
            }
        },
    );
    Ok(finished_volume(
        [h, w, nd],
        data,
        Duration::ZERO,
        start.elapsed(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_bilinearly_at_the_maps_stride() {
        // 3x2 map, 2 channels, stride 2: map pixel (x, y) centred at image (2x + 0.5, 2y + 0.5).
        let data: Vec<f32> = (0..12).map(|v| v as f32).collect();
        let m = FeatureMap {
            width: 3,
            height: 2,
            channels: 2,
            stride: 2,
            data,
        };
        let mut out = [0f32; 2];
        assert!(m.sample_into(0.5, 0.5, &mut out));
        assert_eq!(out, [0.0, 1.0]);
        assert!(m.sample_into(1.5, 0.5, &mut out));
        assert_eq!(out, [1.0, 2.0]);
        assert!(m.sample_into(0.5, 1.5, &mut out));
        assert_eq!(out, [3.0, 4.0]);
        assert!(!m.sample_into(0.0, 0.5, &mut out));
        assert!(!m.sample_into(4.5, 0.5, &mut out));
    }
}
