//! Semi-global matching (Hirschmüller 2008) over the `H x W x N` cost volume
//! of the spherical sweep.
//!
//! Along each path direction `r`,
//! `L_r(p, n) = C(p, n) + min(L_r(p-r, n), L_r(p-r, n±1) + P1, min_k L_r(p-r, k) + P2) - min_k L_r(p-r, k)`,
//! and the aggregated cost is the sum over the paths. The panorama is a
//! closed ring in longitude, so paths wrap around horizontally: the
//! horizontal paths run twice round each row (the first lap only warms the
//! path up) and the vertical and diagonal paths start at the top or bottom
//! row and step across the seam. Costs and path values are 16-bit integers
//! ([`crate::params::COST_SCALE`] units), the path state is one row deep,
//! and the inner loops over `n` are written so that they vectorise.

use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::params::{Directions, SgmParams};
use crate::{CostVolume, StereoError};

/// Path value outside the hypothesis range (never the minimum; `+ P1` still
/// fits in an `i16`).
const SENTINEL: i16 = 0x3FFF;

/// Pixels per parallel task in the vertical and diagonal passes.
const CHUNK: usize = 32;

/// The aggregated cost: `data[(row * width + col) * ndepth + n]`, the sum of
/// all path costs.
#[derive(Debug, Clone, PartialEq)]
pub struct AggregatedVolume {
    pub height: usize,
    pub width: usize,
    pub ndepth: usize,
    pub data: Vec<u16>,
}

impl AggregatedVolume {
    /// The aggregated costs of all hypotheses at one pixel.
    pub fn pixel(&self, row: usize, col: usize) -> &[u16] {
        let i = (row * self.width + col) * self.ndepth;
        &self.data[i..i + self.ndepth]
    }
}

/// One step along a path: `cur` from `prev` (both padded with a
/// [`SENTINEL`] at each end); returns the minimum of `cur`. With AVX2
/// (checked at run time) sixteen hypotheses at a time, the same integer
/// operations ([`step_v3`]).
#[inline]
fn step(cost: &[u16], prev: &[i16], prev_min: i16, p1: i16, p2: i16, cur: &mut [i16]) -> i16 {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        let (done, min) = step_v3(simd, cost, prev, prev_min, p1, p2, cur);
        return min.min(step_from(done, cost, prev, prev_min, p1, p2, cur));
    }
    step_from(0, cost, prev, prev_min, p1, p2, cur)
}

/// [`step`] for hypotheses `start..`, plainly; returns their minimum.
#[inline]
fn step_from(
    start: usize,
    cost: &[u16],
    prev: &[i16],
    prev_min: i16,
    p1: i16,
    p2: i16,
    cur: &mut [i16],
) -> i16 {
    let nd = cost.len();
    let jump = prev_min + p2;
    let (lo, mid, hi) = (
        &prev[start..nd],
        &prev[start + 1..=nd],
        &prev[start + 2..nd + 2],
    );
    let out = &mut cur[start + 1..=nd];
    for ((((o, &c), &l), &m), &h) in out.iter_mut().zip(&cost[start..]).zip(lo).zip(mid).zip(hi) {
        let best = m.min(l.min(h) + p1).min(jump);
        *o = c as i16 + best - prev_min;
    }
    out.iter().copied().fold(i16::MAX, i16::min)
}

/// [`step`] sixteen hypotheses at a time with AVX2 (16-bit lanes, the same
/// operations); returns how many leading hypotheses it did and their minimum.
#[cfg(target_arch = "x86_64")]
fn step_v3(
    simd: pulp::x86::V3,
    cost: &[u16],
    prev: &[i16],
    prev_min: i16,
    p1: i16,
    p2: i16,
    cur: &mut [i16],
) -> (usize, i16) {
    use pulp::{as_arrays, as_arrays_mut, bytemuck::cast};
    simd.vectorize(
        #[inline(always)]
        || {
            let nd = cost.len();
            let (c, _) = as_arrays::<16, u16>(cost);
            let (lo, _) = as_arrays::<16, i16>(&prev[..nd]);
            let (mid, _) = as_arrays::<16, i16>(&prev[1..=nd]);
            let (hi, _) = as_arrays::<16, i16>(&prev[2..nd + 2]);
            let (out, _) = as_arrays_mut::<16, i16>(&mut cur[1..=nd]);
            let n = c
                .len()
                .min(lo.len())
                .min(mid.len())
                .min(hi.len())
                .min(out.len());
            let (p1, jump) = (simd.splat_i16x16(p1), simd.splat_i16x16(prev_min + p2));
            let prev_min = simd.splat_i16x16(prev_min);
            let mut min = simd.splat_i16x16(i16::MAX);
            for i in 0..n {
                let side = simd.wrapping_add_i16x16(simd.min_i16x16(cast(lo[i]), cast(hi[i])), p1);
                let best = simd.min_i16x16(simd.min_i16x16(cast(mid[i]), side), jump);
                let o =
                    simd.wrapping_sub_i16x16(simd.wrapping_add_i16x16(cast(c[i]), best), prev_min);
                min = simd.min_i16x16(min, o);
                out[i] = cast(o);
            }
            let lanes: [i16; 16] = cast(min);
            (n * 16, lanes.into_iter().fold(i16::MAX, i16::min))
        },
    )
}

/// `sum += path` (16-bit; the sum of all paths fits, see
/// [`SgmParams::max_p2`]); sixteen at a time with AVX2.
#[inline]
fn accumulate(sum: &mut [u16], path: &[i16]) {
    let n = sum.len();
    let path = &path[1..=n];
    #[cfg(target_arch = "x86_64")]
    let done = pulp::x86::V3::try_new().map_or(0, |simd| {
        use pulp::{as_arrays, as_arrays_mut, bytemuck::cast};
        simd.vectorize(
            #[inline(always)]
            || {
                let (s, _) = as_arrays_mut::<16, u16>(sum);
                let (l, _) = as_arrays::<16, i16>(path);
                let k = s.len().min(l.len());
                for i in 0..k {
                    s[i] = cast(simd.wrapping_add_u16x16(cast(s[i]), cast(l[i])));
                }
                k * 16
            },
        )
    });
    #[cfg(not(target_arch = "x86_64"))]
    let done = 0;
    for (s, &l) in sum[done..].iter_mut().zip(&path[done..]) {
        *s = s.wrapping_add(l as u16);
    }
}

/// Runs `f` with AVX2 enabled where the CPU has it (checked at run time), so that the
/// [`step`]s and [`accumulate`]s of a whole row inline into its loops instead of being called
/// one pixel at a time.
#[inline(always)]
fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return simd.vectorize(f);
    }
    f()
}

/// A path state for one pixel: zeros inside, sentinels at the ends (the
/// state "before" the first pixel of a path, so that `L = C` there).
fn start_state(nd: usize) -> Vec<i16> {
    let mut v = vec![0i16; nd + 2];
    v[0] = SENTINEL;
    v[nd + 1] = SENTINEL;
    v
}

/// Both horizontal paths of one row, twice round the ring.
fn horizontal_row(cost: &[u16], sum: &mut [u16], nd: usize, p1: i16, p2: i16) {
    with_avx2(
        #[inline(always)]
        || horizontal_row_plain(cost, sum, nd, p1, p2),
    );
}

/// [`horizontal_row`]'s loops.
#[inline(always)]
fn horizontal_row_plain(cost: &[u16], sum: &mut [u16], nd: usize, p1: i16, p2: i16) {
    let w = cost.len() / nd;
    for forward in [true, false] {
        let mut prev = start_state(nd);
        let mut cur = start_state(nd);
        let mut prev_min = 0i16;
        for lap in 0..2 {
            for k in 0..w {
                let x = if forward { k } else { w - 1 - k };
                let c = &cost[x * nd..(x + 1) * nd];
                prev_min = step(c, &prev, prev_min, p1, p2, &mut cur);
                if lap == 1 {
                    accumulate(&mut sum[x * nd..(x + 1) * nd], &cur);
                }
                std::mem::swap(&mut prev, &mut cur);
            }
        }
    }
}

/// The vertical and diagonal paths that run down (`dy = 1`) or up the
/// rows, with column offsets `dxs`; one row of path state per direction.
fn vertical_pass(cost: &CostVolume, sum: &mut [u16], dxs: &[isize], down: bool, p1: i16, p2: i16) {
    let (w, h, nd) = (cost.width, cost.height, cost.ndepth);
    let nd2 = nd + 2;
    let ndir = dxs.len();
    // [col][dir][nd + 2] and [col][dir].
    let mut prev: Vec<i16> = (0..w * ndir).flat_map(|_| start_state(nd)).collect();
    let mut cur = prev.clone();
    let mut prev_min = vec![0i16; w * ndir];
    let mut cur_min = prev_min.clone();
    let row_len = w * nd;
    for k in 0..h {
        let y = if down { k } else { h - 1 - k };
        let cost_row = &cost.data[y * row_len..(y + 1) * row_len];
        let sum_row = &mut sum[y * row_len..(y + 1) * row_len];
        let (prev_ref, prev_min_ref) = (&prev, &prev_min);
        cur.par_chunks_mut(CHUNK * ndir * nd2)
            .zip(cur_min.par_chunks_mut(CHUNK * ndir))
            .zip(sum_row.par_chunks_mut(CHUNK * nd))
            .enumerate()
            .for_each(|(chunk, ((cur, cur_min), sum))| {
                with_avx2(
                    #[inline(always)]
                    || {
                        let x0 = chunk * CHUNK;
                        for (j, s) in sum.chunks_exact_mut(nd).enumerate() {
                            let x = x0 + j;
                            let c = &cost_row[x * nd..(x + 1) * nd];
                            for (dir, &dx) in dxs.iter().enumerate() {
                                // The previous pixel on the path is (y - dy, x - dx).
                                let xs = (x as isize - dx).rem_euclid(w as isize) as usize;
                                let src = (xs * ndir + dir) * nd2;
                                let dst = (j * ndir + dir) * nd2;
                                let m = step(
                                    c,
                                    &prev_ref[src..src + nd2],
                                    prev_min_ref[xs * ndir + dir],
                                    p1,
                                    p2,
                                    &mut cur[dst..dst + nd2],
                                );
                                cur_min[j * ndir + dir] = m;
                                accumulate(s, &cur[dst..dst + nd2]);
                            }
                        }
                    },
                );
            });
        std::mem::swap(&mut prev, &mut cur);
        std::mem::swap(&mut prev_min, &mut cur_min);
    }
}

/// Aggregates `cost` along 4 or 8 wrapping paths; returns the summed volume
/// and the time taken.
///
/// # Errors
/// [`StereoError::Penalties`] for invalid penalties,
/// [`StereoError::Volume`] for an inconsistent volume.
pub fn aggregate(
    cost: &CostVolume,
    params: &SgmParams,
) -> Result<(AggregatedVolume, Duration), StereoError> {
    aggregate_in(cost, params, Vec::new())
}

/// [`aggregate`] in `buffer` (any content; its memory is reused, which spares a frame the
/// page faults of a fresh volume).
///
/// # Errors
/// As [`aggregate`].
pub fn aggregate_in(
    cost: &CostVolume,
    params: &SgmParams,
    buffer: Vec<u16>,
) -> Result<(AggregatedVolume, Duration), StereoError> {
    params.validate()?;
    let (w, h, nd) = (cost.width, cost.height, cost.ndepth);
    if nd < 2 || w == 0 || h == 0 || cost.data.len() != w * h * nd {
        return Err(StereoError::Volume(format!(
            "{} values for {h} x {w} x {nd}",
            cost.data.len()
        )));
    }
    let start = Instant::now();
    let (p1, p2) = (params.p1_units(), params.p2_units());
    let mut sum = buffer;
    sum.clear();
    sum.resize(w * h * nd, 0);
    sum.par_chunks_mut(w * nd)
        .zip(cost.data.par_chunks(w * nd))
        .for_each(|(s, c)| horizontal_row(c, s, nd, p1, p2));
    let dxs: &[isize] = match params.directions {
        Directions::Four => &[0],
        Directions::Eight => &[-1, 0, 1],
    };
    vertical_pass(cost, &mut sum, dxs, true, p1, p2);
    vertical_pass(cost, &mut sum, dxs, false, p1, p2);
    Ok((
        AggregatedVolume {
            height: h,
            width: w,
            ndepth: nd,
            data: sum,
        },
        start.elapsed(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::COST_SCALE;

    fn volume(h: usize, w: usize, nd: usize, f: impl Fn(usize, usize, usize) -> f32) -> CostVolume {
        let mut data = Vec::with_capacity(h * w * nd);
        for y in 0..h {
            for x in 0..w {
                for n in 0..nd {
                    data.push((f(y, x, n) * COST_SCALE).round() as u16);
                }
            }
        }
        CostVolume {
            height: h,
            width: w,
            ndepth: nd,
            data,
        }
    }

    #[test]
    fn a_step_and_its_sum_equal_the_plain_loops_for_any_depth_count() {
        let mut rng = omnimvs_core::rng::SplitMix64::new(21);
        for nd in [2, 15, 16, 17, 64, 192, 203] {
            let cost: Vec<u16> = (0..nd).map(|_| rng.below(2048) as u16).collect();
            let mut prev = start_state(nd);
            for v in &mut prev[1..=nd] {
                *v = rng.below(3000) as i16;
            }
            let prev_min = prev[1..=nd].iter().copied().min().unwrap();
            let (mut fast, mut plain) = (start_state(nd), start_state(nd));
            let m_fast = step(&cost, &prev, prev_min, 100, 2000, &mut fast);
            let m_plain = step_from(0, &cost, &prev, prev_min, 100, 2000, &mut plain);
            assert_eq!((m_fast, &fast), (m_plain, &plain), "nd {nd}");
            let mut sum: Vec<u16> = (0..nd).map(|_| rng.below(60_000) as u16).collect();
            let mut want = sum.clone();
            accumulate(&mut sum, &fast);
            for (s, &l) in want.iter_mut().zip(&fast[1..=nd]) {
                *s = s.wrapping_add(l as u16);
            }
            assert_eq!(sum, want, "nd {nd}");
        }
    }
    #[test]
    fn zero_penalties_sum_the_cost_once_per_path() {
        let c = volume(5, 7, 4, |y, x, n| {
            ((y * 7 + x * 3 + n * 5) % 11) as f32 / 11.0
        });
        for (dirs, k) in [(Directions::Four, 4u16), (Directions::Eight, 8)] {
            let p = SgmParams {
                p1: 0.0,
                p2: 0.0,
                directions: dirs,
                ..SgmParams::default()
            };
            let (agg, _) = aggregate(&c, &p).unwrap();
            // With no penalty every path value is C + min(prev) - min(prev) = C
            // (min over all of prev), except min_k - min = 0: L = C exactly.
            for (a, &cv) in agg.data.iter().zip(&c.data) {
                assert_eq!(*a, k * cv);
            }
        }
    }

    #[test]
    fn smoothing_fills_a_pixel_with_a_misleading_cost() {
        // Everywhere the best hypothesis is 3, except one pixel whose own cost
        // prefers 7; SGM must recover 3 there. The pixel sits on the seam
        // (column 0), so the wrap-around paths matter.
        let (h, w, nd) = (9, 12, 10);
        let c = volume(h, w, nd, |y, x, n| {
            let target = if (y, x) == (4, 0) { 7 } else { 3 };
            if n == target { 0.1 } else { 0.6 }
        });
        let (agg, _) = aggregate(&c, &SgmParams::default()).unwrap();
        let px = agg.pixel(4, 0);
        let best = (0..nd).min_by_key(|&n| px[n]).unwrap();
        assert_eq!(best, 3);
    }

    #[test]
    fn horizontal_paths_wrap_around() {
        // Without wrap-around, column 0 of the rightward path would see no
        // predecessor; on the ring it sees column w-1. A 1-row volume
        // isolates the horizontal paths (vertical ones are single pixels).
        let (h, w, nd) = (1, 6, 3);
        let c = volume(
            h,
            w,
            nd,
            |_, x, n| if x == w - 1 && n == 0 { 0.0 } else { 0.5 },
        );
        let p = SgmParams {
            p1: 1.0,
            p2: 1.0,
            directions: Directions::Four,
            ..SgmParams::default()
        };
        let (agg, _) = aggregate(&c, &p).unwrap();
        let px = agg.pixel(0, 0);
        assert!(
            px[0] < px[1],
            "column 0 inherits column w-1's preference: {px:?}"
        );
    }
}
