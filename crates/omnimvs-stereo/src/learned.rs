//! Learned matching costs: one cost-volume driver for every learned cost, and the MC-CNN-style
//! cost of per-camera feature maps compared across the cameras that see a sphere point.
//!
//! A learned cost says what it computes on one sweep sphere for a band of output rows
//! (`SphereCost`); the driver runs it over the grid's rows and the spheres of the sweep step
//! and writes the fixed-point volume that SGM reads. Two implement it: the feature maps' cost
//! here and the SweepNet-style head of [`crate::sweepnet`].
//!
//! A [`FeatureExtractor`] (implemented by the MC-CNN-style network of `omnimvs-net`) turns each
//! camera's gray image into a dense feature map, computed once per frame on the fisheye image
//! (a siamese tower: the same weights for every camera). For every output pixel and
//! hypothesis, each camera's map is sampled bilinearly where the pixel's ray meets the sphere
//! (the same [`SphereProjector`] as ZNCC), and the cost is `(1 - cos) / 2` averaged over the
//! pairs of cameras that both see the point, [`NO_PAIR_COST`] where fewer than two do: the
//! same `[0, 1]` scale as the ZNCC cost, so SGM and its penalties apply unchanged.

use std::fmt::Debug;
use std::ops::Range;
use std::time::{Duration, Instant};

use omnimvs_core::GrayImage;
use omnimvs_core::interp::sample_channels_inside;
use omnimvs_sweep::SphereProjector;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use rayon::prelude::*;

use crate::cost::{NO_PAIR_COST, camera_pairs, fill_odd_hypotheses, finished_volume};
use crate::params::{SweepStep, cost_units};
use crate::{CameraView, CostTimings, CostVolume, StereoError};

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

/// What a learned cost computes on one sweep sphere; [`learned_cost_volume`] does the rest
/// (the tasks over the grid's rows, the spheres of the sweep step, the fixed-point volume).
pub(crate) trait SphereCost: Sync {
    /// Output rows computed together: one task's rows and one call of [`Self::costs`].
    const ROWS: usize;
    /// Per-thread buffers.
    type Scratch: Default + Send;

    /// The costs (in `[0, 1]`, [`NO_PAIR_COST`] where no camera pair sees the point) of
    /// output rows `rows`, all columns, on the sphere of inverse depth `inv_depth` (1/m) into
    /// `out`, `[(row - rows.start) * width + col]` (`s`: this thread's buffers).
    fn costs(&self, rows: Range<usize>, inv_depth: f32, s: &mut Self::Scratch, out: &mut [f32]);
}

/// The cost volume of a frame by a learned cost: every sphere of `hyps` (every other one with
/// [`SweepStep::EveryOther`], the odd ones filled from their neighbours), [`SphereCost::ROWS`]
/// rows per task.
pub(crate) fn learned_cost_volume<C: SphereCost>(
    grid: &EquirectGrid,
    hyps: &InvDepthHypotheses,
    sweep: SweepStep,
    cost: &C,
) -> (CostVolume, CostTimings) {
    let (w, h, nd) = (grid.width, grid.height, hyps.count);
    let step = sweep.stride();
    let inv_depths: Vec<f32> = (0..nd).map(|n| hyps.inv_depth(n as f64) as f32).collect();
    let start = Instant::now();
    let mut data = vec![0u16; w * h * nd];
    data.par_chunks_mut(C::ROWS * w * nd)
        .enumerate()
        .for_each_init(
            || (C::Scratch::default(), Vec::new()),
            |(scratch, costs), (task, out)| {
                let rows = task * C::ROWS..(task * C::ROWS + C::ROWS).min(h);
                costs.resize(rows.len() * w, 0.0);
                for n in (0..nd).step_by(step) {
                    cost.costs(rows.clone(), inv_depths[n], scratch, costs);
                    for (i, &c) in costs.iter().enumerate() {
                        out[i * nd + n] = cost_units(c);
                    }
                }
                if step == 2 {
                    out.chunks_exact_mut(nd).for_each(fill_odd_hypotheses);
                }
            },
        );
    finished_volume([h, w, nd], data, Duration::ZERO, start.elapsed())
}

/// The feature maps' cost: `(1 - cos) / 2` of the unit feature vectors averaged over the camera
/// pairs that both see the point.
struct FeatureCost<'a> {
    width: usize,
    projectors: &'a [SphereProjector],
    views: &'a [CameraView],
    maps: &'a [FeatureMap],
    channels: usize,
    pairs: Vec<(usize, usize)>,
}

/// Per-thread buffers of [`FeatureCost`]: one row's fisheye positions in a camera (`[col]`),
/// every camera's unit features (`[cam][col][channel]`) and whether it sees the point
/// (`[cam][col]`).
#[derive(Default)]
struct FeatureScratch {
    fisheye_col: Vec<f32>,
    fisheye_row: Vec<f32>,
    table_pos: Vec<f32>,
    features: Vec<f32>,
    seen: Vec<bool>,
}

impl SphereCost for FeatureCost<'_> {
    const ROWS: usize = 1;
    type Scratch = FeatureScratch;

    fn costs(&self, rows: Range<usize>, inv_depth: f32, s: &mut FeatureScratch, out: &mut [f32]) {
        let (w, ch, ncam) = (self.width, self.channels, self.maps.len());
        s.fisheye_col.resize(w, 0.0);
        s.fisheye_row.resize(w, 0.0);
        s.table_pos.resize(w, 0.0);
        s.features.resize(ncam * w * ch, 0.0);
        s.seen.resize(ncam * w, false);
        for (i, row) in rows.enumerate() {
            for cam in 0..ncam {
                self.projectors[cam].project_run(
                    row * w,
                    inv_depth,
                    &mut s.fisheye_col,
                    &mut s.fisheye_row,
                    &mut s.table_pos,
                );
                for x in 0..w {
                    let k = cam * w + x;
                    let f = &mut s.features[k * ch..(k + 1) * ch];
                    let (c, r) = (s.fisheye_col[x], s.fisheye_row[x]);
                    s.seen[k] = self.views[cam].sample(c, r).is_some()
                        && self.maps[cam].sample_into(c, r, f);
                    if s.seen[k] {
                        let norm = f.iter().map(|v| v * v).sum::<f32>().sqrt();
                        let inv = if norm > 1e-12 { 1.0 / norm } else { 0.0 };
                        f.iter_mut().for_each(|v| *v *= inv);
                    }
                }
            }
            let (feat, seen) = (&s.features, &s.seen);
            for (x, o) in out[i * w..(i + 1) * w].iter_mut().enumerate() {
                let (mut sum, mut count) = (0f32, 0u32);
                for &(a, b) in &self.pairs {
                    let (ka, kb) = (a * w + x, b * w + x);
                    if seen[ka] && seen[kb] {
                        let fa = &feat[ka * ch..(ka + 1) * ch];
                        let fb = &feat[kb * ch..(kb + 1) * ch];
                        let cos: f32 = fa.iter().zip(fb).map(|(p, q)| p * q).sum();
                        sum += 0.5 * (1.0 - cos.clamp(-1.0, 1.0));
                        count += 1;
                    }
                }
                *o = if count > 0 {
                    sum / count as f32
                } else {
                    NO_PAIR_COST
                };
            }
        }
    }
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
    let cost = FeatureCost {
        width: grid.width,
        projectors,
        views,
        maps,
        channels: ch,
        pairs: camera_pairs(ncam),
    };
    Ok(learned_cost_volume(grid, hyps, sweep, &cost))
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
