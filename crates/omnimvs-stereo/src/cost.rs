//! The ZNCC matching cost over the sweep spheres.
//!
//! For every output pixel and hypothesis, each camera's normalised image is
//! sampled (bilinearly) where the pixel's ray meets the sphere; the ZNCC of
//! the `patch x patch` windows of every pair of cameras that both see the
//! whole window gives a cost `(1 - zncc) / 2` in `[0, 1]`, averaged over those
//! pairs. Where fewer than two cameras see the window, the cost is
//! [`NO_PAIR_COST`] (0.5, the expected cost of unrelated patches: no
//! evidence either way, so SGM fills the pixel from its neighbours).
//!
//! Window sums use running sums (down the rows, then along each row with
//! wrap-around, since longitude is a ring), so the cost per pixel does not
//! depend on the patch size. Rows of the grid beyond the top and bottom are
//! not there: windows there are clipped to the rows that exist.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use rayon::prelude::*;

use crate::params::{COST_SCALE, SweepStep};
use crate::{CameraView, SphereProjector, StereoError};

/// Cost where fewer than two cameras see the whole window.
pub const NO_PAIR_COST: f32 = 0.5;

/// Added to each window's variance (in units of the normalised image, whose
/// variance is 1) so that ZNCC of nearly flat patches tends to 0 instead of
/// amplifying noise.
pub const ZNCC_VARIANCE_EPS: f32 = 1e-3;

/// Spheres whose costs are computed together before being written into the
/// `[row][col][n]` volume (bounds the scratch memory).
const SPHERE_GROUP: usize = 16;

/// A cost volume in fixed point: `data[(row * width + col) * ndepth + n]`,
/// cost times [`COST_SCALE`].
#[derive(Debug, Clone, PartialEq)]
pub struct CostVolume {
    pub height: usize,
    pub width: usize,
    pub ndepth: usize,
    pub data: Vec<u16>,
}

impl CostVolume {
    /// The costs of all hypotheses at one pixel.
    pub fn pixel(&self, row: usize, col: usize) -> &[u16] {
        let i = (row * self.width + col) * self.ndepth;
        &self.data[i..i + self.ndepth]
    }

    /// One cost as a float in `[0, 1]`.
    pub fn cost(&self, row: usize, col: usize, n: usize) -> f32 {
        f32::from(self.pixel(row, col)[n]) / COST_SCALE
    }

    /// Bytes held.
    pub fn byte_len(&self) -> usize {
        self.data.len() * 2
    }
}

/// Wall-clock split of the cost stage.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CostTimings {
    /// Projecting and sampling the images on the spheres.
    pub warp: Duration,
    /// Window sums, ZNCC and writing the volume.
    pub cost: Duration,
}

/// Everything needed to match one frame.
pub struct Matcher<'a> {
    pub grid: EquirectGrid,
    pub projectors: &'a [SphereProjector],
    pub views: &'a [CameraView],
    /// Half the patch side.
    pub radius: usize,
}

/// Per-thread buffers of one sphere's computation.
struct Scratch {
    ncam: usize,
    patch: usize,
    width: usize,
    pairs: Vec<(usize, usize)>,
    /// `[cam][slot][col]`: sampled values of the last `patch` rows.
    values: Vec<f32>,
    /// Same layout: 1 where the sample is missing.
    missing: Vec<f32>,
    /// `[col][quantity]`: sums down the window's rows.
    colsum: Vec<f32>,
    /// `[quantity]`: the running window sum along the row.
    window: Vec<f32>,
    mean: Vec<f32>,
    inv_std: Vec<f32>,
    complete: Vec<bool>,
}

impl Scratch {
    fn new(ncam: usize, patch: usize, width: usize) -> Self {
        let mut pairs = Vec::new();
        for a in 0..ncam {
            for b in a + 1..ncam {
                pairs.push((a, b));
            }
        }
        let q = 3 * ncam + pairs.len();
        Self {
            ncam,
            patch,
            width,
            pairs,
            values: vec![0.0; ncam * patch * width],
            missing: vec![0.0; ncam * patch * width],
            colsum: vec![0.0; width * q],
            window: vec![0.0; q],
            mean: vec![0.0; ncam],
            inv_std: vec![0.0; ncam],
            complete: vec![false; ncam],
        }
    }

    /// Quantities per column: per camera sum, sum of squares, missing count;
    /// per pair the sum of products.
    fn quantities(&self) -> usize {
        3 * self.ncam + self.pairs.len()
    }

    fn row_slice(&self, cam: usize, slot: usize) -> std::ops::Range<usize> {
        let start = (cam * self.patch + slot) * self.width;
        start..start + self.width
    }

    /// Adds (`sign = 1`) or removes (`-1`) the row in `slot` from the column sums.
    fn accumulate(&mut self, slot: usize, sign: f32) {
        let (ncam, q, w) = (self.ncam, self.quantities(), self.width);
        for cam in 0..ncam {
            let r = self.row_slice(cam, slot);
            let vals = &self.values[r.clone()];
            let miss = &self.missing[r];
            for (x, (&v, &m)) in vals.iter().zip(miss).enumerate() {
                let base = x * q;
                self.colsum[base + cam] += sign * v;
                self.colsum[base + ncam + cam] += sign * v * v;
                self.colsum[base + 2 * ncam + cam] += sign * m;
            }
        }
        for (k, &(a, b)) in self.pairs.iter().enumerate() {
            let ra = self.row_slice(a, slot);
            let rb = self.row_slice(b, slot);
            let va = &self.values[ra];
            let vb = &self.values[rb];
            let col = &mut self.colsum[3 * ncam + k..];
            for x in 0..w {
                col[x * q] += sign * va[x] * vb[x];
            }
        }
    }
}

impl Matcher<'_> {
    fn patch(&self) -> usize {
        2 * self.radius + 1
    }

    /// Samples grid row `row` of every camera on the sphere `inv_depth` into
    /// the ring slot of that row.
    fn warp_row(&self, s: &mut Scratch, row: usize, inv_depth: f32) {
        let w = self.grid.width;
        let slot = row % s.patch;
        for (cam, (proj, view)) in self.projectors.iter().zip(self.views).enumerate() {
            let r = s.row_slice(cam, slot);
            let (vals, miss) = (&mut s.values[r.clone()], &mut s.missing[r]);
            for x in 0..w {
                let sample = proj
                    .project(row * w + x, inv_depth)
                    .and_then(|(c, r)| view.sample(c, r));
                (vals[x], miss[x]) = match sample {
                    Some(v) => (v, 0.0),
                    None => (0.0, 1.0),
                };
            }
        }
    }

    /// The costs of one output row from the column sums, wrapping around in
    /// longitude.
    fn cost_row(&self, s: &mut Scratch, row: usize, out: &mut [u16]) {
        let (w, h, r) = (self.grid.width, self.grid.height, self.radius);
        let q = s.quantities();
        let ncam = s.ncam;
        let rows = (row + r).min(h - 1) - row.saturating_sub(r) + 1;
        let inv_n = 1.0 / (rows * self.patch()) as f32;
        s.window.fill(0.0);
        for k in 0..self.patch() {
            let x = (k + w - r) % w;
            for (acc, v) in s.window.iter_mut().zip(&s.colsum[x * q..(x + 1) * q]) {
                *acc += v;
            }
        }
        for (x, dst) in out.iter_mut().enumerate() {
            for c in 0..ncam {
                let mean = s.window[c] * inv_n;
                let var = (s.window[ncam + c] * inv_n - mean * mean).max(0.0);
                s.mean[c] = mean;
                s.inv_std[c] = 1.0 / (var + ZNCC_VARIANCE_EPS).sqrt();
                s.complete[c] = s.window[2 * ncam + c] < 0.5;
            }
            let (mut sum, mut count) = (0f32, 0u32);
            for (k, &(a, b)) in s.pairs.iter().enumerate() {
                if s.complete[a] && s.complete[b] {
                    let cov = s.window[3 * ncam + k] * inv_n - s.mean[a] * s.mean[b];
                    let zncc = (cov * s.inv_std[a] * s.inv_std[b]).clamp(-1.0, 1.0);
                    sum += 0.5 * (1.0 - zncc);
                    count += 1;
                }
            }
            let cost = if count > 0 {
                sum / count as f32
            } else {
                NO_PAIR_COST
            };
            *dst = (cost * COST_SCALE).round() as u16;
            // Slide the window one column right.
            let enter = (x + r + 1) % w;
            let leave = (x + w - r) % w;
            let (e, l) = (&s.colsum[enter * q..(enter + 1) * q], &s.colsum[leave * q..(leave + 1) * q]);
            for ((acc, a), b) in s.window.iter_mut().zip(e).zip(l) {
                *acc += a - b;
            }
        }
    }

    /// The `[row][col]` cost slice of the sphere at `inv_depth` (1/m); returns
    /// the time spent warping and matching.
    fn sphere_slice(&self, s: &mut Scratch, inv_depth: f32, out: &mut [u16]) -> (Duration, Duration) {
        let (w, h, r) = (self.grid.width, self.grid.height, self.radius);
        let (mut warp, mut cost) = (Duration::ZERO, Duration::ZERO);
        s.colsum.fill(0.0);
        for row in 0..r.min(h) {
            let t0 = Instant::now();
            self.warp_row(s, row, inv_depth);
            let t1 = Instant::now();
            s.accumulate(row % s.patch, 1.0);
            warp += t1 - t0;
            cost += t1.elapsed();
        }
        for row in 0..h {
            let t0 = Instant::now();
            if row > r {
                s.accumulate((row - r - 1) % s.patch, -1.0);
            }
            let t1 = Instant::now();
            let add = row + r;
            if add < h {
                self.warp_row(s, add, inv_depth);
            }
            let t2 = Instant::now();
            if add < h {
                s.accumulate(add % s.patch, 1.0);
            }
            self.cost_row(s, row, &mut out[row * w..(row + 1) * w]);
            warp += t2 - t1;
            cost += (t1 - t0) + t2.elapsed();
        }
        (warp, cost)
    }

    /// The cost volume of all `hyps.count` hypotheses (computing every other
    /// one with [`SweepStep::EveryOther`]).
    ///
    /// # Errors
    /// [`StereoError::Volume`] when the grid is narrower than the patch or
    /// fewer than two cameras are given.
    pub fn cost_volume(
        &self,
        hyps: &InvDepthHypotheses,
        sweep: SweepStep,
    ) -> Result<(CostVolume, CostTimings), StereoError> {
        let (w, h) = (self.grid.width, self.grid.height);
        let ncam = self.views.len();
        if ncam < 2 || self.projectors.len() != ncam {
            return Err(StereoError::TooFewCameras { found: ncam });
        }
        if w < self.patch() + 1 {
            return Err(StereoError::Volume(format!(
                "grid width {w}: expected more than the patch size {}",
                self.patch()
            )));
        }
        let nd = hyps.count;
        let step = match sweep {
            SweepStep::All => 1,
            SweepStep::EveryOther => 2,
        };
        let computed: Vec<usize> = (0..nd).step_by(step).collect();
        let plane = w * h;
        let mut data = vec![0u16; plane * nd];
        let warp_ns = AtomicU64::new(0);
        let cost_ns = AtomicU64::new(0);
        let start = Instant::now();
        let mut transpose = Duration::ZERO;
        let group_len = SPHERE_GROUP.min(computed.len());
        let mut slices = vec![0u16; group_len * plane];
        for group in computed.chunks(group_len) {
            slices[..group.len() * plane]
                .par_chunks_mut(plane)
                .zip(group.par_iter())
                .for_each_init(
                    || Scratch::new(ncam, self.patch(), w),
                    |scratch, (out, &n)| {
                        let d = hyps.inv_depth(n as f64) as f32;
                        let (tw, tc) = self.sphere_slice(scratch, d, out);
                        warp_ns.fetch_add(tw.as_nanos() as u64, Ordering::Relaxed);
                        cost_ns.fetch_add(tc.as_nanos() as u64, Ordering::Relaxed);
                    },
                );
            let t = Instant::now();
            let slices = &slices;
            data.par_chunks_mut(w * nd).enumerate().for_each(|(row, dst)| {
                for (x, px) in dst.chunks_exact_mut(nd).enumerate() {
                    let i = row * w + x;
                    for (g, &n) in group.iter().enumerate() {
                        px[n] = slices[g * plane + i];
                    }
                }
            });
            transpose += t.elapsed();
        }
        if step == 2 {
            let t = Instant::now();
            data.par_chunks_mut(nd).for_each(|px| {
                for n in (1..nd).step_by(2) {
                    px[n] = if n + 1 < nd {
                        ((u32::from(px[n - 1]) + u32::from(px[n + 1])).div_ceil(2)) as u16
                    } else {
                        px[n - 1]
                    };
                }
            });
            transpose += t.elapsed();
        }
        // Split the wall time of the parallel part by the threads' shares.
        let total = start.elapsed();
        let parallel = total.saturating_sub(transpose);
        let (tw, tc) = (
            warp_ns.load(Ordering::Relaxed) as f64,
            cost_ns.load(Ordering::Relaxed) as f64,
        );
        let warp_share = if tw + tc > 0.0 { tw / (tw + tc) } else { 0.0 };
        let warp = parallel.mul_f64(warp_share);
        Ok((
            CostVolume {
                height: h,
                width: w,
                ndepth: nd,
                data,
            },
            CostTimings {
                warp,
                cost: total - warp,
            },
        ))
    }
}
