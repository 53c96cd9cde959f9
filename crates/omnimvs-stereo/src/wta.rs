//! Winner-take-all with sub-index parabola refinement, and a confidence map.

use rayon::prelude::*;

use crate::AggregatedVolume;

/// The estimated hypothesis index per pixel and its confidence.
#[derive(Debug, Clone, PartialEq)]
pub struct IndexMap {
    pub height: usize,
    pub width: usize,
    /// Fractional hypothesis index `n_hat` in `[0, N-1]`, row-major.
    pub index: Vec<f32>,
    /// `1 - best / second`, in `[0, 1]`: `best` the smallest aggregated cost,
    /// `second` the smallest one more than one hypothesis away from it. 0
    /// means another, distant inverse depth fits as well (ambiguous), values
    /// near 1 a clear single minimum.
    pub confidence: Vec<f32>,
}

/// Index and confidence of one pixel.
fn pixel(costs: &[u16]) -> (f32, f32) {
    let nd = costs.len();
    // The first smallest cost, then the smallest more than one hypothesis away: minima over
    // contiguous runs, which vectorise.
    let lowest = |run: &[u16]| run.iter().copied().min().unwrap_or(u16::MAX);
    let min = lowest(costs);
    let best = costs.iter().position(|&c| c == min).unwrap_or(0);
    let second = lowest(&costs[..best.saturating_sub(1)]).min(lowest(&costs[(best + 2).min(nd)..]));
    let mut index = best as f32;
    if best > 0 && best + 1 < nd {
        let (c0, c1, c2) = (
            f32::from(costs[best - 1]),
            f32::from(costs[best]),
            f32::from(costs[best + 1]),
        );
        let curvature = c0 - 2.0 * c1 + c2;
        if curvature > 0.0 {
            index += (0.5 * (c0 - c2) / curvature).clamp(-0.5, 0.5);
        }
    }
    let confidence = if second == u16::MAX || second == 0 {
        0.0
    } else {
        1.0 - f32::from(costs[best]) / f32::from(second)
    };
    (index, confidence)
}

/// Winner-take-all over the hypotheses of every pixel, refined by fitting a
/// parabola through the best cost and its two neighbours (the offset is
/// clamped to ±0.5; the ends of the range are not refined).
pub fn winner_take_all(agg: &AggregatedVolume) -> IndexMap {
    let n = agg.width * agg.height;
    let mut index = vec![0f32; n];
    let mut confidence = vec![0f32; n];
    index
        .par_iter_mut()
        .zip(confidence.par_iter_mut())
        .zip(agg.data.par_chunks(agg.ndepth))
        .for_each(|((i, c), costs)| (*i, *c) = pixel(costs));
    IndexMap {
        height: agg.height,
        width: agg.width,
        index,
        confidence,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_recovers_a_fractional_minimum() {
        // Samples of (n - 4.3)^2 + 10.
        let costs: Vec<u16> = (0..10)
            .map(|n| ((n as f32 - 4.3).powi(2) * 100.0 + 10.0).round() as u16)
            .collect();
        let (i, conf) = pixel(&costs);
        assert!((i - 4.3).abs() < 0.01, "{i}");
        assert!(conf > 0.5);
        // A flat cost has no confidence; an end minimum is not refined.
        assert_eq!(pixel(&[7, 7, 7, 7]).1, 0.0);
        assert_eq!(pixel(&[1, 5, 9, 9]).0, 0.0);
        // Two equal distant minima: confidence 0.
        assert_eq!(pixel(&[3, 9, 9, 9, 3]).1, 0.0);
    }

    #[test]
    fn best_and_second_are_the_plain_definitions() {
        // The first strict minimum, and the smallest cost more than one hypothesis from it.
        let plain = |costs: &[u16]| {
            let mut best = 0;
            for (n, &c) in costs.iter().enumerate() {
                if c < costs[best] {
                    best = n;
                }
            }
            let second = (0..costs.len())
                .filter(|&n| n + 1 < best || n > best + 1)
                .map(|n| costs[n])
                .min()
                .unwrap_or(u16::MAX);
            (best, second)
        };
        let mut rng = omnimvs_core::rng::SplitMix64::new(5);
        for len in [2, 3, 4, 17, 192] {
            for _ in 0..200 {
                // Few distinct values, so that ties and neighbours are common.
                let costs: Vec<u16> = (0..len).map(|_| (rng.next_f64() * 6.0) as u16).collect();
                let (best, second) = plain(&costs);
                let (index, confidence) = pixel(&costs);
                assert!((index - best as f32).abs() <= 0.5, "{costs:?}: {index}");
                let expected = if second == u16::MAX || second == 0 {
                    0.0
                } else {
                    1.0 - f32::from(costs[best]) / f32::from(second)
                };
                assert_eq!(confidence, expected, "{costs:?}");
            }
        }
    }
}
