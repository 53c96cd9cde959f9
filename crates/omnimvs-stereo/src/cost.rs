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

use omnimvs_sweep::SphereProjector;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use rayon::prelude::*;

use crate::params::{COST_SCALE, SweepStep, cost_units};
use crate::{CameraView, RunSampler, StereoError};

/// Cost where fewer than two cameras see the whole window.
pub const NO_PAIR_COST: f32 = 0.5;

/// Added to each window's variance (in units of the normalised image, whose
/// variance is 1) so that ZNCC of nearly flat patches tends to 0 instead of
/// amplifying noise.
pub const ZNCC_VARIANCE_EPS: f32 = 1e-3;

/// Spheres whose costs are computed together before being written into the
/// `[row][col][n]` volume (bounds the scratch memory).
const SPHERE_GROUP: usize = 32;

/// Runs `start..end` of columns of one grid row.
type Runs = Vec<(usize, usize)>;

/// Spheres one thread computes side by side (see [`Matcher::sphere_group`]).
const INTERLEAVE: usize = 4;

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

/// A cost stage's answer: the `height x width x ndepth` volume of `data` and its timings,
/// `warp` of the `total` spent sampling the images.
pub(crate) fn finished_volume(
    [height, width, ndepth]: [usize; 3],
    data: Vec<u16>,
    warp: Duration,
    total: Duration,
) -> (CostVolume, CostTimings) {
    let volume = CostVolume {
        height,
        width,
        ndepth,
        data,
    };
    let cost = total.saturating_sub(warp);
    (volume, CostTimings { warp, cost })
}

/// The pairs of `ncam` cameras in the order every cost averages and every learned cost's
/// features list them: `(0, 1), (0, 2), ..., (1, 2), ...`.
pub fn camera_pairs(ncam: usize) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    for a in 0..ncam {
        for b in a + 1..ncam {
            pairs.push((a, b));
        }
    }
    pairs
}

/// With [`SweepStep::EveryOther`]: the cost of each odd hypothesis of one pixel's `px` as the
/// mean of its two even neighbours (rounded up), the last one a copy of the one before.
pub(crate) fn fill_odd_hypotheses(px: &mut [u16]) {
    let nd = px.len();
    for n in (1..nd).step_by(2) {
        px[n] = if n + 1 < nd {
            ((u32::from(px[n - 1]) + u32::from(px[n + 1])).div_ceil(2)) as u16
        } else {
            px[n - 1]
        };
    }
}

/// Everything needed to match one frame.
pub struct Matcher<'a> {
    pub grid: EquirectGrid,
    pub projectors: &'a [SphereProjector],
    pub views: &'a [CameraView],
    /// Half the patch side.
    pub radius: usize,
}

/// Per-thread buffers of a few spheres' computation (`lanes` of them, side
/// by side): every per-column array holds, for each grid column, one value
/// per sphere (`[col][lane]`, so a row is `width = cols * lanes` floats).
/// All the arithmetic is element by element along such rows, except the
/// window sums along a row, which run the spheres' chains as one vector.
struct Scratch {
    ncam: usize,
    /// Spheres side by side.
    lanes: usize,
    /// Floats per row: grid columns times `lanes`.
    width: usize,
    /// Rows in the ring of samples: the window's `patch` and the one that
    /// is leaving it, so that a new row can be warped before the old one is
    /// subtracted and both happen in one pass ([`Self::update`]).
    slots: usize,
    pairs: Vec<(usize, usize)>,
    /// `[cam][slot][col]`: sampled values of the last `slots` rows.
    values: Vec<f32>,
    /// Same layout: 1 where the sample is missing.
    missing: Vec<f32>,
    /// `[quantity][col]`: sums down the window's rows.
    colsum: Vec<f32>,
    /// `[quantity][col]`: full window sums of the current row.
    boxsum: Vec<f32>,
    /// `[cam][col]`: window mean and `1 / std` of each camera.
    mean: Vec<f32>,
    inv_std: Vec<f32>,
    /// `[col]`: sum of pair costs and number of pairs.
    cost_sum: Vec<f32>,
    pair_count: Vec<f32>,
    /// Sampling one camera's row on one sphere.
    sampler: RunSampler,
}

impl Scratch {
    fn new(ncam: usize, patch: usize, cols: usize, lanes: usize) -> Self {
        let width = cols * lanes;
        let pairs = camera_pairs(ncam);
        // Quantities per column: per camera sum, sum of squares, missing
        // count; per pair the sum of products.
        let q = 3 * ncam + pairs.len();
        Self {
            ncam,
            lanes,
            width,
            pairs,
            slots: patch + 1,
            values: vec![0.0; ncam * (patch + 1) * width],
            missing: vec![0.0; ncam * (patch + 1) * width],
            colsum: vec![0.0; q * width],
            boxsum: vec![0.0; q * width],
            mean: vec![0.0; ncam * width],
            inv_std: vec![0.0; ncam * width],
            cost_sum: vec![0.0; width],
            pair_count: vec![0.0; width],
            sampler: RunSampler::new(cols),
        }
    }

    fn row_slice(&self, cam: usize, slot: usize) -> std::ops::Range<usize> {
        let start = (cam * self.slots + slot) * self.width;
        start..start + self.width
    }

    fn quantity(&self, q: usize) -> std::ops::Range<usize> {
        q * self.width..(q + 1) * self.width
    }

    /// Removes the row in slot `remove` from the column sums and adds the
    /// row in slot `add`.
    fn update(&mut self, remove: Option<usize>, add: Option<usize>) {
        match (remove, add) {
            (Some(old), Some(new)) => self.replace(old, new),
            (Some(old), None) => self.accumulate(old, -1.0),
            (None, Some(new)) => self.accumulate(new, 1.0),
            (None, None) => {}
        }
    }

    /// `accumulate(old, -1.0)` then `accumulate(new, 1.0)` in one pass over
    /// the column sums: per element the same operations in the same order
    /// (`-1 * v` is `-v` exactly), so the sums are bit-identical.
    fn replace(&mut self, old: usize, new: usize) {
        let (ncam, w) = (self.ncam, self.width);
        for cam in 0..ncam {
            let (ro, rn) = (self.row_slice(cam, old), self.row_slice(cam, new));
            let (vo, mo) = (&self.values[ro.clone()], &self.missing[ro]);
            let (vn, mn) = (&self.values[rn.clone()], &self.missing[rn]);
            let (s1, rest) = self.colsum.split_at_mut((ncam + cam) * w);
            let sum = &mut s1[cam * w..(cam + 1) * w];
            let (s2, s3) = rest.split_at_mut(ncam * w);
            let (sq, ms) = (&mut s2[..w], &mut s3[..w]);
            for i in 0..w {
                sum[i] += -vo[i];
                sum[i] += vn[i];
                sq[i] += -vo[i] * vo[i];
                sq[i] += vn[i] * vn[i];
                ms[i] += -mo[i];
                ms[i] += mn[i];
            }
        }
        for (k, &(a, b)) in self.pairs.iter().enumerate() {
            let (ao, bo) = (
                &self.values[self.row_slice(a, old)],
                &self.values[self.row_slice(b, old)],
            );
            let (an, bn) = (
                &self.values[self.row_slice(a, new)],
                &self.values[self.row_slice(b, new)],
            );
            let r = (3 * ncam + k) * w;
            let col = &mut self.colsum[r..r + w];
            for i in 0..w {
                col[i] += -ao[i] * bo[i];
                col[i] += an[i] * bn[i];
            }
        }
    }

    /// Adds (`sign = 1`) or removes (`-1`) the row in `slot` from the column sums.
    fn accumulate(&mut self, slot: usize, sign: f32) {
        let ncam = self.ncam;
        for cam in 0..ncam {
            let r = self.row_slice(cam, slot);
            let vals = &self.values[r.clone()];
            let miss = &self.missing[r];
            let (s1, rest) = self.colsum.split_at_mut((ncam + cam) * self.width);
            let sum = &mut s1[cam * self.width..(cam + 1) * self.width];
            let (s2, s3) = rest.split_at_mut(ncam * self.width);
            let sq = &mut s2[..self.width];
            let ms = &mut s3[..self.width];
            for ((((s, q), m), &v), &mv) in sum.iter_mut().zip(sq).zip(ms).zip(vals).zip(miss) {
                *s += sign * v;
                *q += sign * v * v;
                *m += sign * mv;
            }
        }
        for (k, &(a, b)) in self.pairs.iter().enumerate() {
            let va = &self.values[self.row_slice(a, slot)];
            let vb = &self.values[self.row_slice(b, slot)];
            let r = (3 * ncam + k) * self.width;
            let col = &mut self.colsum[r..r + self.width];
            for ((c, &x), &y) in col.iter_mut().zip(va).zip(vb) {
                *c += sign * x * y;
            }
        }
    }
}

/// Quantities whose running sums advance side by side in
/// [`row_window_sums`]: independent additions that hide each other's latency.
const LANES: usize = 6;

/// Window sums along one grid row for every quantity: `boxsum[j][x]` is the
/// sum of `colsum[j][x - r ..= x + r]`, columns taken round the ring, for
/// each of the `L` spheres side by side (`[quantity][col][lane]`, rows of
/// `w * L` floats, `w > 2 r + 1`).
///
/// Each quantity of each sphere is one running sum from column 0, in exactly
/// the order of [`row_window_sums_reference`] (so the results are
/// bit-identical); the `L` spheres' chains advance as one vector and
/// [`LANES`] quantities' vectors side by side. The columns entering and
/// leaving the window are read from contiguous slices: the row splits into
/// three runs where neither index wraps.
#[inline(always)]
fn row_window_sums<const L: usize>(colsum: &[f32], boxsum: &mut [f32], w: usize, r: usize) {
    let span = w * L;
    debug_assert!(
        w > 2 * r + 1 && colsum.len() == boxsum.len() && colsum.len().is_multiple_of(span)
    );
    // (first column, first entering column, first leaving column, length).
    let runs = [
        (0, r + 1, w - r, r),
        (r, 2 * r + 1, 0, w - 2 * r - 1),
        (w - r - 1, 0, w - 2 * r - 1, r + 1),
    ];
    let mut rows = colsum.chunks_exact(span).map(|c| c.as_chunks::<L>().0).zip(
        boxsum
            .chunks_exact_mut(span)
            .map(|b| b.as_chunks_mut::<L>().0),
    );
    loop {
        let mut c: [&[[f32; L]]; LANES] = [&[]; LANES];
        let mut b: [&mut [[f32; L]]; LANES] = Default::default();
        let mut lanes = 0;
        for (cj, bj) in rows.by_ref().take(LANES) {
            c[lanes] = cj;
            b[lanes] = bj;
            lanes += 1;
        }
        if lanes == 0 {
            break;
        }
        let mut acc = [[0f32; L]; LANES];
        for k in 0..2 * r + 1 {
            let x = (k + w - r) % w;
            for l in 0..lanes {
                for g in 0..L {
                    acc[l][g] += c[l][x][g];
                }
            }
        }
        for &(x0, enter, leave, len) in &runs {
            if lanes == LANES {
                // The common case: all lanes' chains in one loop body.
                let e: [&[[f32; L]]; LANES] = std::array::from_fn(|l| &c[l][enter..enter + len]);
                let v: [&[[f32; L]]; LANES] = std::array::from_fn(|l| &c[l][leave..leave + len]);
                let o = b.each_mut().map(|bl| &mut bl[x0..x0 + len]);
                for i in 0..len {
                    for l in 0..LANES {
                        o[l][i] = acc[l];
                        for g in 0..L {
                            acc[l][g] += e[l][i][g] - v[l][i][g];
                        }
                    }
                }
                continue;
            }
            for l in 0..lanes {
                let (bl, cl) = (&mut b[l][x0..x0 + len], c[l]);
                let (e, v) = (&cl[enter..enter + len], &cl[leave..leave + len]);
                let mut a = acc[l];
                for ((o, ein), out) in bl.iter_mut().zip(e).zip(v) {
                    *o = a;
                    for g in 0..L {
                        a[g] += ein[g] - out[g];
                    }
                }
                acc[l] = a;
            }
        }
    }
}

/// [`row_window_sums`] for four spheres side by side with SSE (part of every
/// x86-64): each quantity's four chains are one `__m128`, added with the same
/// operations in the same order (the compiler keeps the generic version's
/// `[f32; 4]` chains in memory, lane by lane).
#[cfg(target_arch = "x86_64")]
fn row_window_sums_x4(
    sse: pulp::core_arch::x86::Sse,
    colsum: &[f32],
    boxsum: &mut [f32],
    w: usize,
    r: usize,
) {
    use pulp::bytemuck::cast;
    use std::arch::x86_64::__m128;
    let span = w * 4;
    debug_assert!(
        w > 2 * r + 1 && colsum.len() == boxsum.len() && colsum.len().is_multiple_of(span)
    );
    let runs = [
        (0, r + 1, w - r, r),
        (r, 2 * r + 1, 0, w - 2 * r - 1),
        (w - r - 1, 0, w - 2 * r - 1, r + 1),
    ];
    let mut rows = colsum.chunks_exact(span).map(|c| c.as_chunks::<4>().0).zip(
        boxsum
            .chunks_exact_mut(span)
            .map(|b| b.as_chunks_mut::<4>().0),
    );
    loop {
        let mut c: [&[[f32; 4]]; LANES] = [&[]; LANES];
        let mut b: [&mut [[f32; 4]]; LANES] = Default::default();
        let mut lanes = 0;
        for (cj, bj) in rows.by_ref().take(LANES) {
            c[lanes] = cj;
            b[lanes] = bj;
            lanes += 1;
        }
        if lanes == 0 {
            break;
        }
        let mut acc: [__m128; LANES] = [sse._mm_setzero_ps(); LANES];
        for k in 0..2 * r + 1 {
            let x = (k + w - r) % w;
            for l in 0..lanes {
                acc[l] = sse._mm_add_ps(acc[l], cast(c[l][x]));
            }
        }
        for &(x0, enter, leave, len) in &runs {
            if lanes == LANES {
                let e: [&[[f32; 4]]; LANES] = std::array::from_fn(|l| &c[l][enter..enter + len]);
                let v: [&[[f32; 4]]; LANES] = std::array::from_fn(|l| &c[l][leave..leave + len]);
                let o = b.each_mut().map(|bl| &mut bl[x0..x0 + len]);
                for i in 0..len {
                    for l in 0..LANES {
                        o[l][i] = cast(acc[l]);
                        acc[l] =
                            sse._mm_add_ps(acc[l], sse._mm_sub_ps(cast(e[l][i]), cast(v[l][i])));
                    }
                }
                continue;
            }
            for l in 0..lanes {
                let (bl, cl) = (&mut b[l][x0..x0 + len], c[l]);
                let (e, v) = (&cl[enter..enter + len], &cl[leave..leave + len]);
                let mut a = acc[l];
                for ((o, &ein), &out) in bl.iter_mut().zip(e).zip(v) {
                    *o = cast(a);
                    a = sse._mm_add_ps(a, sse._mm_sub_ps(cast(ein), cast(out)));
                }
                acc[l] = a;
            }
        }
    }
}

/// [`row_window_sums`] written plainly (the reference of its tests): every
/// quantity's and sphere's running sum, one at a time, indices taken modulo
/// the width; `lanes` spheres side by side.
#[cfg(test)]
fn row_window_sums_reference(colsum: &[f32], boxsum: &mut [f32], w: usize, r: usize, lanes: usize) {
    let at = |j: usize, x: usize, g: usize| (j * w + x) * lanes + g;
    for j in 0..colsum.len() / (w * lanes) {
        for g in 0..lanes {
            let mut acc = 0f32;
            for k in 0..2 * r + 1 {
                acc += colsum[at(j, (k + w - r) % w, g)];
            }
            for x in 0..w {
                let enter = (x + r + 1) % w;
                let leave = (x + w - r) % w;
                boxsum[at(j, x, g)] = acc;
                acc += colsum[at(j, enter, g)] - colsum[at(j, leave, g)];
            }
        }
    }
}

/// One camera's window sums along a row: of its samples, their squares and
/// its missing samples.
struct WindowSums<'a> {
    sum: &'a [f32],
    sq: &'a [f32],
    miss: &'a [f32],
}

impl WindowSums<'_> {
    /// Window mean and `1 / std` (0 where a sample is missing) from column
    /// `start` on, `inv_n` being 1 / the window's sample count.
    #[inline(always)]
    fn moments(&self, start: usize, inv_n: f32, mean: &mut [f32], inv_std: &mut [f32]) {
        let (sum, sq, miss) = (&self.sum[start..], &self.sq[start..], &self.miss[start..]);
        let (mean, inv_std) = (&mut mean[start..], &mut inv_std[start..]);
        for ((((m, is), &a), &b), &k) in mean.iter_mut().zip(inv_std).zip(sum).zip(sq).zip(miss) {
            let mu = a * inv_n;
            let var = (b * inv_n - mu * mu).max(0.0);
            *m = mu;
            // A window with a missing sample gets inv_std = 0 and is
            // skipped by the pairs.
            *is = if k < 0.5 {
                1.0 / (var + ZNCC_VARIANCE_EPS).sqrt()
            } else {
                0.0
            };
        }
    }

    /// [`Self::moments`] eight columns at a time with AVX2, the same
    /// operations in the same order; returns how many leading columns it did.
    #[cfg(target_arch = "x86_64")]
    fn moments_v3(
        &self,
        simd: pulp::x86::V3,
        inv_n: f32,
        mean: &mut [f32],
        inv_std: &mut [f32],
    ) -> usize {
        use pulp::{as_arrays, as_arrays_mut, bytemuck::cast};
        simd.vectorize(
            #[inline(always)]
            || {
                let (sum, _) = as_arrays::<8, f32>(self.sum);
                let (sq, _) = as_arrays::<8, f32>(self.sq);
                let (miss, _) = as_arrays::<8, f32>(self.miss);
                let (mean, _) = as_arrays_mut::<8, f32>(mean);
                let (inv_std, _) = as_arrays_mut::<8, f32>(inv_std);
                let n = sum
                    .len()
                    .min(sq.len())
                    .min(miss.len())
                    .min(mean.len())
                    .min(inv_std.len());
                let inv_n = simd.splat_f32x8(inv_n);
                let zero = simd.splat_f32x8(0.0);
                let one = simd.splat_f32x8(1.0);
                let half = simd.splat_f32x8(0.5);
                let eps = simd.splat_f32x8(ZNCC_VARIANCE_EPS);
                for i in 0..n {
                    let mu = simd.mul_f32x8(cast(sum[i]), inv_n);
                    let b = simd.mul_f32x8(cast(sq[i]), inv_n);
                    let var = simd.max_f32x8(simd.sub_f32x8(b, simd.mul_f32x8(mu, mu)), zero);
                    mean[i] = cast(mu);
                    let is = simd.div_f32x8(one, simd.sqrt_f32x8(simd.add_f32x8(var, eps)));
                    let complete = simd.cmp_lt_f32x8(cast(miss[i]), half);
                    inv_std[i] = cast(simd.select_f32x8(complete, is, zero));
                }
                n * 8
            },
        )
    }
}

/// A pair of cameras' window sums of products, means and `1 / std`s along a row.
struct PairSums<'a> {
    prod: &'a [f32],
    mean: [&'a [f32]; 2],
    inv_std: [&'a [f32]; 2],
}

impl PairSums<'_> {
    /// Adds the pair's cost `(1 - zncc) / 2` and 1 to `cost_sum` and
    /// `pair_count` from column `start` on, where both windows are complete.
    #[inline(always)]
    fn add_costs(&self, start: usize, inv_n: f32, cost_sum: &mut [f32], pair_count: &mut [f32]) {
        let ([ma, mb], [ia, ib]) = (self.mean, self.inv_std);
        for x in start..cost_sum.len() {
            let norm = ia[x] * ib[x];
            let cov = self.prod[x] * inv_n - ma[x] * mb[x];
            let zncc = (cov * norm).clamp(-1.0, 1.0);
            let used = if norm > 0.0 { 1.0 } else { 0.0 };
            cost_sum[x] += used * 0.5 * (1.0 - zncc);
            pair_count[x] += used;
        }
    }

    /// [`Self::add_costs`] eight columns at a time with AVX2, the same
    /// operations in the same order; returns how many leading columns it did.
    #[cfg(target_arch = "x86_64")]
    fn add_costs_v3(
        &self,
        simd: pulp::x86::V3,
        inv_n: f32,
        cost_sum: &mut [f32],
        pair_count: &mut [f32],
    ) -> usize {
        use pulp::{as_arrays, as_arrays_mut, bytemuck::cast};
        simd.vectorize(
            #[inline(always)]
            || {
                let (prod, _) = as_arrays::<8, f32>(self.prod);
                let (ma, _) = as_arrays::<8, f32>(self.mean[0]);
                let (mb, _) = as_arrays::<8, f32>(self.mean[1]);
                let (ia, _) = as_arrays::<8, f32>(self.inv_std[0]);
                let (ib, _) = as_arrays::<8, f32>(self.inv_std[1]);
                let (cost_sum, _) = as_arrays_mut::<8, f32>(cost_sum);
                let (pair_count, _) = as_arrays_mut::<8, f32>(pair_count);
                let n = cost_sum.len().min(pair_count.len()).min(prod.len());
                let n = n.min(ma.len()).min(mb.len()).min(ia.len()).min(ib.len());
                let inv_n = simd.splat_f32x8(inv_n);
                let zero = simd.splat_f32x8(0.0);
                let one = simd.splat_f32x8(1.0);
                let minus_one = simd.splat_f32x8(-1.0);
                let half = simd.splat_f32x8(0.5);
                for i in 0..n {
                    let norm = simd.mul_f32x8(cast(ia[i]), cast(ib[i]));
                    let cov = simd.sub_f32x8(
                        simd.mul_f32x8(cast(prod[i]), inv_n),
                        simd.mul_f32x8(cast(ma[i]), cast(mb[i])),
                    );
                    // clamp(-1, 1) as `f32::clamp` does it (NaN stays NaN).
                    let z = simd.mul_f32x8(cov, norm);
                    let z = simd.select_f32x8(simd.cmp_lt_f32x8(z, minus_one), minus_one, z);
                    let z = simd.select_f32x8(simd.cmp_gt_f32x8(z, one), one, z);
                    let used = simd.select_f32x8(simd.cmp_gt_f32x8(norm, zero), one, zero);
                    let cost = simd.mul_f32x8(simd.mul_f32x8(used, half), simd.sub_f32x8(one, z));
                    cost_sum[i] = cast(simd.add_f32x8(cast(cost_sum[i]), cost));
                    pair_count[i] = cast(simd.add_f32x8(cast(pair_count[i]), used));
                }
                n * 8
            },
        )
    }
}

impl Matcher<'_> {
    fn patch(&self) -> usize {
        2 * self.radius + 1
    }

    /// Samples grid row `row` of every camera on the spheres `inv_depths`
    /// (one per lane of `s`; lanes beyond them are left as they are) into
    /// the ring slot of that row. `visible[cam][row]` are the runs of columns where the
    /// camera can see some sphere of the sweep ([`SphereProjector::visible_runs`]); the
    /// others are missing in every lane, as sampling would find them.
    fn warp_rows(&self, s: &mut Scratch, row: usize, inv_depths: &[f32], visible: &[Vec<Runs>]) {
        let w = self.grid.width;
        let lanes = s.lanes;
        let slot = row % s.slots;
        for (cam, view) in self.views.iter().enumerate() {
            let runs = &visible[cam][row];
            let r = s.row_slice(cam, slot);
            if runs.iter().map(|&(a, b)| b - a).sum::<usize>() < w {
                s.values[r.clone()].fill(0.0);
                s.missing[r.clone()].fill(1.0);
            }
            for &(a, b) in runs {
                let n = b - a;
                for (g, &d) in inv_depths.iter().enumerate().take(lanes) {
                    let (run_v, run_m) =
                        s.sampler
                            .sample(&self.projectors[cam], view, row * w + a, n, d);
                    let span = r.start + a * lanes..r.start + b * lanes;
                    let (vals, miss) = (&mut s.values[span.clone()], &mut s.missing[span]);
                    let lanes_out = vals
                        .chunks_exact_mut(lanes)
                        .zip(miss.chunks_exact_mut(lanes));
                    for ((v, m), (&rv, &rm)) in lanes_out.zip(run_v.iter().zip(run_m.iter())) {
                        (v[g], m[g]) = (rv, rm);
                    }
                }
            }
        }
    }

    /// The costs of one output row from the column sums, wrapping around in
    /// longitude.
    ///
    /// `out` is `[row][col][lane]`: the costs of all of `s`'s lanes.
    fn cost_row(&self, s: &mut Scratch, row: usize, out: &mut [u16]) {
        let (gw, h, r) = (self.grid.width, self.grid.height, self.radius);
        let ncam = s.ncam;
        if s.lanes == INTERLEAVE {
            #[cfg(target_arch = "x86_64")]
            match pulp::core_arch::x86::Sse::try_new() {
                Some(sse) => row_window_sums_x4(sse, &s.colsum, &mut s.boxsum, gw, r),
                None => row_window_sums::<INTERLEAVE>(&s.colsum, &mut s.boxsum, gw, r),
            }
            #[cfg(not(target_arch = "x86_64"))]
            row_window_sums::<INTERLEAVE>(&s.colsum, &mut s.boxsum, gw, r);
        } else {
            debug_assert_eq!(s.lanes, 1);
            row_window_sums::<1>(&s.colsum, &mut s.boxsum, gw, r);
        }
        // From here on element by element along the `[col][lane]` rows.
        let w = s.width;
        // ZNCC, vectorised along the row.
        let rows = (row + r).min(h - 1) - row.saturating_sub(r) + 1;
        let inv_n = 1.0 / (rows * self.patch()) as f32;
        #[cfg(target_arch = "x86_64")]
        let v3 = pulp::x86::V3::try_new();
        for c in 0..ncam {
            let stats = WindowSums {
                sum: &s.boxsum[s.quantity(c)],
                sq: &s.boxsum[s.quantity(ncam + c)],
                miss: &s.boxsum[s.quantity(2 * ncam + c)],
            };
            let mean = &mut s.mean[c * w..(c + 1) * w];
            let inv_std = &mut s.inv_std[c * w..(c + 1) * w];
            #[cfg(target_arch = "x86_64")]
            let done = v3.map_or(0, |simd| stats.moments_v3(simd, inv_n, mean, inv_std));
            #[cfg(not(target_arch = "x86_64"))]
            let done = 0;
            stats.moments(done, inv_n, mean, inv_std);
        }
        s.cost_sum.fill(0.0);
        s.pair_count.fill(0.0);
        for (k, &(a, b)) in s.pairs.iter().enumerate() {
            let pair = PairSums {
                prod: &s.boxsum[s.quantity(3 * ncam + k)],
                mean: [&s.mean[a * w..(a + 1) * w], &s.mean[b * w..(b + 1) * w]],
                inv_std: [
                    &s.inv_std[a * w..(a + 1) * w],
                    &s.inv_std[b * w..(b + 1) * w],
                ],
            };
            #[cfg(target_arch = "x86_64")]
            let done = v3.map_or(0, |simd| {
                pair.add_costs_v3(simd, inv_n, &mut s.cost_sum, &mut s.pair_count)
            });
            #[cfg(not(target_arch = "x86_64"))]
            let done = 0;
            pair.add_costs(done, inv_n, &mut s.cost_sum, &mut s.pair_count);
        }
        let out = &mut out[row * w..(row + 1) * w];
        for ((dst, &sum), &count) in out.iter_mut().zip(&s.cost_sum).zip(&s.pair_count) {
            let cost = if count > 0.0 {
                sum / count
            } else {
                NO_PAIR_COST
            };
            *dst = cost_units(cost);
        }
    }

    /// The costs of a few spheres (`inv_depths`, 1/m, at most `s.lanes`)
    /// into `out`, `[row][col][lane]` (so that moving them into the volume
    /// reads a few neighbouring values per pixel); returns the time
    /// spent warping and matching. The spheres are computed side by side, as
    /// the lanes of `s`: for one grid row, neighbouring spheres sample nearly
    /// the same fisheye pixels, so the images stay in cache, and their window
    /// sums along the row run as one vector.
    fn sphere_group(
        &self,
        s: &mut Scratch,
        inv_depths: &[f32],
        out: &mut [u16],
        visible: &[Vec<Runs>],
    ) -> (Duration, Duration) {
        let (h, r) = (self.grid.height, self.radius);
        let spheres = inv_depths.len().min(s.lanes);
        let (mut warp, mut cost) = (Duration::ZERO, Duration::ZERO);
        s.colsum.fill(0.0);
        // Lanes without a sphere of their own (a short last group) stay
        // empty: every sample missing, so no pair (their costs are not read).
        if spheres < s.lanes {
            s.values.fill(0.0);
            s.missing.fill(1.0);
        }
        for row in 0..r.min(h) {
            let t0 = Instant::now();
            self.warp_rows(s, row, &inv_depths[..spheres], visible);
            let t1 = Instant::now();
            s.accumulate(row % s.slots, 1.0);
            warp += t1 - t0;
            cost += t1.elapsed();
        }
        for row in 0..h {
            // The ring has a slot more than the window, so the new row is
            // warped before the leaving one is subtracted.
            let t0 = Instant::now();
            let add = row + r;
            if add < h {
                self.warp_rows(s, add, &inv_depths[..spheres], visible);
            }
            let t1 = Instant::now();
            let leave = (row > r).then(|| (row - r - 1) % s.slots);
            s.update(leave, (add < h).then(|| add % s.slots));
            self.cost_row(s, row, out);
            warp += t1 - t0;
            cost += t1.elapsed();
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
        self.cost_volume_in(hyps, sweep, Vec::new())
    }

    /// [`Self::cost_volume`] in `buffer` (any content; its memory is reused, which spares a
    /// frame the page faults of a fresh volume).
    ///
    /// # Errors
    /// As [`Self::cost_volume`].
    pub fn cost_volume_in(
        &self,
        hyps: &InvDepthHypotheses,
        sweep: SweepStep,
        buffer: Vec<u16>,
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
        let step = sweep.stride();
        let computed: Vec<usize> = (0..nd).step_by(step).collect();
        let plane = w * h;
        let mut data = buffer;
        data.clear();
        data.resize(plane * nd, 0);
        // Per camera and grid row, the columns where some sphere can be seen.
        let (near, far) = (
            hyps.inv_depth(0.0) as f32,
            hyps.inv_depth((nd - 1) as f64) as f32,
        );
        let visible: Vec<Vec<Runs>> = self
            .projectors
            .iter()
            .map(|p| {
                (0..h)
                    .map(|row| p.visible_runs(row, w, near, far))
                    .collect()
            })
            .collect();
        let warp_ns = AtomicU64::new(0);
        let cost_ns = AtomicU64::new(0);
        let start = Instant::now();
        let mut transpose = Duration::ZERO;
        let group_len = SPHERE_GROUP.min(computed.len());
        // `[chunk of INTERLEAVE spheres][row][col][sphere in the chunk]`.
        let chunk = INTERLEAVE * plane;
        let mut slices = vec![0u16; group_len.div_ceil(INTERLEAVE) * chunk];
        for group in computed.chunks(group_len) {
            slices[..group.len().div_ceil(INTERLEAVE) * chunk]
                .par_chunks_mut(chunk)
                .zip(group.par_chunks(INTERLEAVE))
                .for_each_init(
                    || Scratch::new(ncam, self.patch(), w, INTERLEAVE),
                    |scratch, (out, ns)| {
                        let d: Vec<f32> = ns
                            .iter()
                            .map(|&n| hyps.inv_depth(n as f64) as f32)
                            .collect();
                        let (tw, tc) = self.sphere_group(scratch, &d, out, &visible);
                        warp_ns.fetch_add(tw.as_nanos() as u64, Ordering::Relaxed);
                        cost_ns.fetch_add(tc.as_nanos() as u64, Ordering::Relaxed);
                    },
                );
            let t = Instant::now();
            let slices = &slices;
            data.par_chunks_mut(w * nd)
                .enumerate()
                .for_each(|(row, dst)| {
                    for (x, px) in dst.chunks_exact_mut(nd).enumerate() {
                        let i = row * w + x;
                        for (k, ns) in group.chunks(INTERLEAVE).enumerate() {
                            let src = &slices[k * chunk + i * INTERLEAVE..][..INTERLEAVE];
                            for (&n, &c) in ns.iter().zip(src) {
                                px[n] = c;
                            }
                        }
                    }
                });
            transpose += t.elapsed();
        }
        if step == 2 {
            let t = Instant::now();
            data.par_chunks_mut(nd).for_each(fill_odd_hypotheses);
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
        Ok(finished_volume([h, w, nd], data, warp, total))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use omnimvs_core::rng::SplitMix64;

    #[test]
    fn row_window_sums_equal_the_plain_running_sums_bit_for_bit() {
        let mut rng = SplitMix64::new(15);
        // Widths from the smallest allowed (2r + 2) up, radii 0..=4, and
        // quantity counts that leave 0..3 lanes over (18 is four cameras).
        for (w, r, q) in [
            (2, 0, 1),
            (4, 1, 3),
            (10, 4, 18),
            (11, 4, 5),
            (64, 2, 7),
            (640, 4, 18),
        ] {
            for lanes in [1, INTERLEAVE] {
                let n = q * w * lanes;
                let colsum: Vec<f32> = (0..n)
                    .map(|_| (rng.next_f64() * 200.0 - 100.0) as f32)
                    .collect();
                let (mut fast, mut plain) = (vec![f32::NAN; n], vec![f32::NAN; n]);
                if lanes == 1 {
                    row_window_sums::<1>(&colsum, &mut fast, w, r);
                } else {
                    row_window_sums::<INTERLEAVE>(&colsum, &mut fast, w, r);
                }
                row_window_sums_reference(&colsum, &mut plain, w, r, lanes);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&plain), "w {w} r {r} q {q} lanes {lanes}");
                #[cfg(target_arch = "x86_64")]
                if let (4, Some(simd)) = (lanes, pulp::core_arch::x86::Sse::try_new()) {
                    let mut sse = vec![f32::NAN; n];
                    row_window_sums_x4(simd, &colsum, &mut sse, w, r);
                    assert_eq!(bits(&sse), bits(&plain), "SSE: w {w} r {r} q {q}");
                }
                // And they are window sums round the ring (to rounding).
                let at = |j: usize, x: usize, g: usize| (j * w + x) * lanes + g;
                for j in 0..q {
                    for x in 0..w {
                        for g in 0..lanes {
                            let exact: f64 = (0..2 * r + 1)
                                .map(|k| f64::from(colsum[at(j, (x + w + k - r) % w, g)]))
                                .sum();
                            assert!((f64::from(fast[at(j, x, g)]) - exact).abs() < 1e-2);
                        }
                    }
                }
            }
        }
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn avx2_window_moments_and_pair_costs_equal_the_plain_loops_bit_for_bit() {
        let Some(simd) = pulp::x86::V3::try_new() else {
            eprintln!("no AVX2 here: only the plain loops run");
            return;
        };
        let mut rng = SplitMix64::new(17);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for w in [3, 8, 37, 2560] {
            let mut random = |lo: f64, hi: f64| -> Vec<f32> {
                (0..w)
                    .map(|_| (lo + rng.next_f64() * (hi - lo)) as f32)
                    .collect()
            };
            let inv_n = 1.0 / 81.0;
            let sum = random(-81.0, 81.0);
            // Some windows nearly flat (variance at or below 0 by rounding).
            let mut sq = random(0.0, 300.0);
            for (q, &a) in sq.iter_mut().zip(&sum).step_by(5) {
                *q = a * a * inv_n;
            }
            let miss: Vec<f32> = (0..w)
                .map(|x| if x % 7 == 3 { (x % 3 + 1) as f32 } else { 0.0 })
                .collect();
            let stats = WindowSums {
                sum: &sum,
                sq: &sq,
                miss: &miss,
            };
            let (mut m_fast, mut i_fast) = (vec![f32::NAN; w], vec![f32::NAN; w]);
            let (mut m_plain, mut i_plain) = (vec![f32::NAN; w], vec![f32::NAN; w]);
            let done = stats.moments_v3(simd, inv_n, &mut m_fast, &mut i_fast);
            assert_eq!(done, w / 8 * 8);
            stats.moments(done, inv_n, &mut m_fast, &mut i_fast);
            stats.moments(0, inv_n, &mut m_plain, &mut i_plain);
            assert_eq!(bits(&m_fast), bits(&m_plain), "mean, width {w}");
            assert_eq!(bits(&i_fast), bits(&i_plain), "1 / std, width {w}");
            assert!(i_plain.contains(&0.0) || w < 4);
            // Pairs, with correlations beyond +-1 (clamped) and missing windows.
            let (mb, ib) = (random(-2.0, 2.0), random(0.0, 3.0));
            let prod = random(-400.0, 400.0);
            let pair = PairSums {
                prod: &prod,
                mean: [&m_plain, &mb],
                inv_std: [&i_plain, &ib],
            };
            let (mut c_fast, mut n_fast) = (random(0.0, 3.0), random(0.0, 3.0));
            let (mut c_plain, mut n_plain) = (c_fast.clone(), n_fast.clone());
            let done = pair.add_costs_v3(simd, inv_n, &mut c_fast, &mut n_fast);
            pair.add_costs(done, inv_n, &mut c_fast, &mut n_fast);
            pair.add_costs(0, inv_n, &mut c_plain, &mut n_plain);
            assert_eq!(bits(&c_fast), bits(&c_plain), "cost sums, width {w}");
            assert_eq!(bits(&n_fast), bits(&n_plain), "pair counts, width {w}");
        }
    }

    #[test]
    fn replacing_a_row_equals_removing_then_adding_it_bit_for_bit() {
        let mut rng = SplitMix64::new(16);
        for ncam in [2, 3, 4] {
            let (patch, w) = (3, 37);
            let mut fused = Scratch::new(ncam, patch, w, INTERLEAVE);
            for (v, m) in fused.values.iter_mut().zip(fused.missing.iter_mut()) {
                // Normalised samples, some of them missing (0 with a 1 flag).
                let missing = rng.below(5) == 0;
                *v = if missing {
                    0.0
                } else {
                    (rng.next_f64() * 6.0 - 3.0) as f32
                };
                *m = if missing { 1.0 } else { 0.0 };
            }
            for c in fused.colsum.iter_mut() {
                *c = (rng.next_f64() * 50.0 - 25.0) as f32;
            }
            let mut plain = Scratch::new(ncam, patch, w, INTERLEAVE);
            plain.values.clone_from(&fused.values);
            plain.missing.clone_from(&fused.missing);
            plain.colsum.clone_from(&fused.colsum);
            for (old, new) in [(0, 3), (1, 0), (3, 2)] {
                fused.update(Some(old), Some(new));
                plain.accumulate(old, -1.0);
                plain.accumulate(new, 1.0);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fused.colsum), bits(&plain.colsum), "{ncam} cameras");
            }
        }
    }
}
