//! Hypothesis placement of the cascade's stages: the coarse spheres evenly spaced over the
//! inverse-depth range, a refinement stage's hypotheses around each pixel's estimate, and
//! their stretch to the extremes of the estimates around. The per-pixel projection of those
//! hypotheses into the cameras is [`crate::pixel::PixelSampler`].

use omnimvs_data::edges::neighbour_min_max;

/// `count` hypothesis indices evenly spaced over `0..=N-1` (the coarse spheres).
pub fn coarse_indices(count: usize, num_invdepth: usize) -> Vec<f64> {
    let (last, intervals) = coarse_span(count, num_invdepth);
    (0..count).map(|k| k as f64 * last / intervals).collect()
}

/// The spacing of [`coarse_indices`], in index units of `N`.
pub fn coarse_spacing(count: usize, num_invdepth: usize) -> f64 {
    let (last, intervals) = coarse_span(count, num_invdepth);
    last / intervals
}

/// The last coarse index (`N - 1`) and the number of intervals between the spheres.
fn coarse_span(count: usize, num_invdepth: usize) -> (f64, f64) {
    (
        num_invdepth.saturating_sub(1) as f64,
        count.saturating_sub(1).max(1) as f64,
    )
}

/// `k` per-pixel hypotheses spaced by `interval` around `center` (fractional indices,
/// `[rows * cols]`), shifted as a block to stay inside `0..=N-1`: `[k, rows * cols]`.
pub fn hypotheses_around(center: &[f32], k: usize, interval: f64, num_invdepth: usize) -> Vec<f32> {
    let span = (k.saturating_sub(1)) as f64 * interval;
    let last = num_invdepth.saturating_sub(1) as f64;
    let mut out = vec![0f32; k * center.len()];
    for (i, &c) in center.iter().enumerate() {
        let start = (f64::from(c) - span / 2.0).clamp(0.0, (last - span).max(0.0));
        for j in 0..k {
            out[j * center.len() + i] = (start + j as f64 * interval).min(last) as f32;
        }
    }
    out
}

/// Stretches the outermost of `k` hypotheses per pixel (`index[j * pixels + pixel]`, as
/// [`hypotheses_around`] makes them) to the lowest and highest of `center` (`[rows * cols]`)
/// over the `(2 radius + 1)^2` pixels around each pixel ([`neighbour_min_max`], columns
/// wrapping when `wrap`): the first
/// becomes the lower of itself and that minimum, the last the higher of itself and that
/// maximum. `radius` 0 or `k < 2` leaves the hypotheses as they are.
pub fn stretch_to_neighbours(
    index: &mut [f32],
    center: &[f32],
    k: usize,
    grid: [usize; 2],
    wrap: bool,
    radius: usize,
) {
    let pixels = grid[0] * grid[1];
    if radius == 0 || k < 2 || pixels == 0 || center.len() != pixels || index.len() != k * pixels {
        return;
    }
    let (low, high) = neighbour_min_max(center, grid, wrap, radius);
    let (first, rest) = index.split_at_mut(pixels);
    let last = &mut rest[(k - 2) * pixels..];
    for i in 0..pixels {
        first[i] = first[i].min(low[i]);
        last[i] = last[i].max(high[i]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hypotheses_stay_inside_the_range() {
        let h = hypotheses_around(&[0.5, 100.0, 190.0], 4, 2.0, 192);
        // Plane j, pixel i at h[j * 3 + i].
        assert_eq!([h[0], h[3], h[6], h[9]], [0.0, 2.0, 4.0, 6.0]);
        assert_eq!([h[1], h[4], h[7], h[10]], [97.0, 99.0, 101.0, 103.0]);
        assert_eq!([h[2], h[5], h[8], h[11]], [185.0, 187.0, 189.0, 191.0]);
        let c = coarse_indices(48, 192);
        assert_eq!(c.len(), 48);
        assert_eq!(c[0], 0.0);
        assert!((c[47] - 191.0).abs() < 1e-12);
    }

    #[test]
    fn outermost_hypotheses_reach_the_neighbours_extremes() {
        // A 3 x 4 centre map with a depth edge: 20 on the left, 100 on the right.
        let center = [20.0, 20.0, 100.0, 100.0].repeat(3);
        let k = 3;
        let mut index = hypotheses_around(&center, k, 1.0, 192);
        let even = index.clone();
        stretch_to_neighbours(&mut index, &center, k, [3, 4], false, 1);
        let n = center.len();
        // Column 1 sees 100 at its right: its highest hypothesis reaches it, its lowest stays.
        assert_eq!(
            (index[1], index[n + 1], index[2 * n + 1]),
            (19.0, 20.0, 100.0)
        );
        // Column 2 sees 20 at its left.
        assert_eq!(
            (index[2], index[n + 2], index[2 * n + 2]),
            (20.0, 100.0, 101.0)
        );
        // Column 0 does not see the edge without wrapping, and keeps its even hypotheses.
        assert_eq!(index[0], even[0]);
        assert_eq!(index[2 * n], even[2 * n]);
        // Wrapping, column 0 sees column 3 (100) and column 3 sees column 0 (20).
        let mut wrapped = even.clone();
        stretch_to_neighbours(&mut wrapped, &center, k, [3, 4], true, 1);
        assert_eq!(wrapped[2 * n], 100.0);
        assert_eq!(wrapped[3], 20.0);
        // The middle hypotheses never move, nor does anything with radius 0.
        assert_eq!(&wrapped[n..2 * n], &even[n..2 * n]);
        let mut same = even.clone();
        stretch_to_neighbours(&mut same, &center, k, [3, 4], true, 0);
        assert_eq!(same, even);
        // Rows: a step between rows reaches the row above and below only within the radius.
        let rows = [10.0, 10.0, 10.0, 50.0, 90.0];
        let center: Vec<f32> = rows.iter().flat_map(|&v| [v, v]).collect();
        let mut index = hypotheses_around(&center, 2, 1.0, 192);
        stretch_to_neighbours(&mut index, &center, 2, [5, 2], true, 1);
        let n = center.len();
        let highest: Vec<f32> = (0..5).map(|y| index[n + 2 * y]).collect();
        let lowest: Vec<f32> = (0..5).map(|y| index[2 * y]).collect();
        assert_eq!(highest, [10.5, 10.5, 50.0, 90.0, 90.5]);
        assert_eq!(lowest, [9.5, 9.5, 9.5, 10.0, 50.0]);
    }
}
