//! Semi-global aggregation of the coarse stage's own distribution (`coarse_score_sgm`).
//!
//! The coarse stage's 2D encoder-decoder sees a few coarse pixels around each one; where the
//! cameras' evidence is weak over a region (a textureless face, a repeated texture), its
//! distribution there is flat or wrong, while the pixels around the region are sure. Semi-global
//! matching carries that certainty along 8 paths (Hirschmüller 2008). Here its matching cost
//! is the network's own: the negative log-probability of each sphere, in nats, clamped at
//! [`SCORE_SGM_MAX_COST`]. The aggregated costs `S` (their sum over the paths, each pixel's
//! least subtracted) then lower the network's log-probabilities: the new distribution is
//! `softmax(log p - S / temperature)`, and its soft argmax the coarse answer the refinement
//! stages start from.
//!
//! Measured on the bundled network (`research/cascade.md`, things
//! validation frames 481-490 of `things-s101`, `p1` 1, `p2` 4, temperature 8): the coarse
//! answers off by more than 20 index units fall from 15.0 % of the pixels to 12.3 % and the
//! coarse MAE from 5.94 to 5.48 with sky scored as index 0; but over the pixels the
//! reference's rules score (no sky) the MAE rises (5.07 to 5.27; 11.3 % off by more than 20
//! against 12.1 %): the paths fill sky next to objects and fix some regions, and swallow
//! small objects into what surrounds them. It has no weights and no gradient (it runs at
//! inference only, [`super::CascadeNet`]'s forward passes without `training`), and the
//! bundled network does not use it.

use omnimvs_stereo::params::{COST_SCALE, Directions, cost_units};
use omnimvs_stereo::{CostVolume, SgmParams, aggregate};

use crate::config::ScoreSgm;
use crate::error::NetError;

/// The largest matching cost (nats of negative log-probability) the aggregation sees: a sphere
/// the network gives less than `e^-8` (3e-4) of a pixel's weight costs as much as one it rules
/// out. The study found the same answers with 4 nats and with no clamp.
pub const SCORE_SGM_MAX_COST: f32 = 8.0;

/// The aggregated log-scores of a coarse distribution `prob` (`K` spheres of `h x w` values,
/// sphere-major, the spheres in index order, each pixel's values summing to 1): `K x h x w`
/// values `log p - S / temperature`, sphere-major, whose softmax over the spheres is the new
/// distribution. Columns wrap around (longitude is a ring).
///
/// # Errors
/// [`NetError::Shape`] when the sizes disagree; [`NetError::Stereo`] when the aggregation
/// refuses the penalties or the volume (fewer than 2 spheres).
pub fn aggregated_scores(
    prob: &[f32],
    spheres: usize,
    [h, w]: [usize; 2],
    sgm: &ScoreSgm,
) -> Result<Vec<f32>, NetError> {
    let plane = h * w;
    if prob.len() != spheres * plane {
        return Err(NetError::Shape {
            what: "coarse distribution to aggregate".into(),
            expected: vec![spheres, h, w],
            actual: vec![prob.len()],
        });
    }
    let log_p = |k: usize, pixel: usize| prob[k * plane + pixel].max(f32::MIN_POSITIVE).ln();
    // Costs in [0, 1]: nats over the clamp, as the aggregation's 16-bit units want them.
    let mut data = vec![0u16; plane * spheres];
    for (pixel, costs) in data.chunks_exact_mut(spheres).enumerate() {
        for (k, cost) in costs.iter_mut().enumerate() {
            let nats = (-log_p(k, pixel)).clamp(0.0, SCORE_SGM_MAX_COST);
            *cost = cost_units(nats / SCORE_SGM_MAX_COST);
        }
    }
    let summed = aggregate_eight(
        data,
        spheres,
        [h, w],
        [sgm.p1 / SCORE_SGM_MAX_COST, sgm.p2 / SCORE_SGM_MAX_COST],
    )?;
    // One unit of the sums is 1 / COST_SCALE of the clamp, in nats.
    let nats_per_unit = SCORE_SGM_MAX_COST / COST_SCALE / sgm.temperature;
    let mut out = vec![0f32; spheres * plane];
    for (pixel, sums) in summed.chunks_exact(spheres).enumerate() {
        let best = sums.iter().copied().min().unwrap_or(0);
        for (k, &sum) in sums.iter().enumerate() {
            let excess = f32::from(sum - best) * nats_per_unit;
            out[k * plane + pixel] = log_p(k, pixel) - excess;
        }
    }
    Ok(out)
}

/// Semi-global aggregation along 8 paths (columns wrapping: longitude is a ring) of a cost
/// volume of `planes` costs per pixel in the 16-bit units of `omnimvs_stereo`
/// ([`cost_units`], pixel-major, `h x w` pixels), penalties `[p1, p2]` in the same units: the
/// sums over the paths, pixel-major. What the aggregated photometric cue
/// ([`super::photo::AggregatedCue`]) and the aggregated coarse distribution share.
///
/// # Errors
/// [`NetError::Stereo`] when the aggregation refuses the penalties or the volume (fewer than 2
/// planes).
pub(crate) fn aggregate_eight(
    data: Vec<u16>,
    planes: usize,
    [h, w]: [usize; 2],
    [p1, p2]: [f32; 2],
) -> Result<Vec<u16>, NetError> {
    let volume = CostVolume {
        height: h,
        width: w,
        ndepth: planes,
        data,
    };
    let params = SgmParams {
        p1,
        p2,
        directions: Directions::Eight,
        ..SgmParams::default()
    };
    Ok(aggregate(&volume, &params)?.0.data)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn softmax_at(scores: &[f32], spheres: usize, plane: usize, pixel: usize) -> Vec<f32> {
        let s: Vec<f32> = (0..spheres).map(|k| scores[k * plane + pixel]).collect();
        let max = s.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let e: Vec<f32> = s.iter().map(|v| (v - max).exp()).collect();
        let sum: f32 = e.iter().sum();
        e.iter().map(|v| v / sum).collect()
    }

    /// A region of flat distributions inside sure pixels takes their sphere; the sure pixels
    /// keep theirs.
    #[test]
    fn flat_region_takes_the_sure_surroundings_sphere() {
        let (spheres, h, w) = (8, 12, 24);
        let plane = h * w;
        let sure = 5;
        let mut prob = vec![0f32; spheres * plane];
        for r in 0..h {
            for c in 0..w {
                let flat = (4..8).contains(&r) && (8..16).contains(&c);
                for k in 0..spheres {
                    prob[k * plane + r * w + c] = if flat {
                        1.0 / spheres as f32
                    } else if k == sure {
                        0.93
                    } else {
                        0.01
                    };
                }
            }
        }
        let sgm = ScoreSgm {
            p1: 1.0,
            p2: 4.0,
            temperature: 8.0,
        };
        let scores = aggregated_scores(&prob, spheres, [h, w], &sgm).unwrap();
        // Uniform before (1/8 each); now peaked at the surroundings' sphere.
        let inside = softmax_at(&scores, spheres, plane, 5 * w + 11);
        let best = (0..spheres).max_by(|&a, &b| inside[a].total_cmp(&inside[b]));
        assert_eq!(best, Some(sure), "{inside:?}");
        assert!(inside[sure] > 0.4, "{inside:?}");
        let outside = softmax_at(&scores, spheres, plane, w + 2);
        assert!(outside[sure] > 0.93, "{outside:?}");
    }

    /// Penalties the 16-bit aggregation cannot hold and a volume of the wrong size are refused.
    #[test]
    fn bad_sizes_and_penalties_are_refused() {
        let sgm = ScoreSgm {
            p1: 1.0,
            p2: 4.0,
            temperature: 8.0,
        };
        let err = aggregated_scores(&[0.5; 10], 2, [2, 3], &sgm).unwrap_err();
        assert!(err.to_string().contains("coarse distribution"), "{err}");
        let huge = ScoreSgm { p2: 1000.0, ..sgm };
        assert!(aggregated_scores(&[0.5; 12], 2, [2, 3], &huge).is_err());
    }
}
