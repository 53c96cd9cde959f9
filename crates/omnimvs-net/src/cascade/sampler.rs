//! Hypothesis placement of the cascade's stages: the coarse spheres evenly spaced over the
//! inverse-depth range, a refinement stage's hypotheses around each pixel's estimate, and
//! their stretch to the extremes of the estimates around. The per-pixel projection of those
//! hypotheses into the cameras is [`crate::pixel::PixelSampler`].

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
}
