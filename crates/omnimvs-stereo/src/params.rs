use serde::{Deserialize, Serialize};

use crate::StereoError;

/// Fixed-point scale of the matching cost: a cost of `1.0` (the largest
/// ZNCC cost, perfectly anti-correlated patches) is stored as this many
/// units of a `u16`.
pub const COST_SCALE: f32 = 512.0;

/// A matching cost in `[0, 1]` as the `u16` units of a cost volume ([`COST_SCALE`], rounded
/// to nearest): what every volume of this crate stores, and what a caller building one for
/// [`crate::aggregate`] must store.
#[inline]
pub fn cost_units(cost: f32) -> u16 {
    (cost * COST_SCALE + 0.5) as u16
}

/// Default `P1` (small inverse-depth changes), in matching-cost units
/// (`(1 - zncc) / 2`, in `[0, 1]`). Tuned on generated validation rooms only
/// (the `tune_sgm` study, `research/study-programs.md`; README of this crate).
pub const DEFAULT_P1: f32 = 0.1;

/// Default `P2` (jumps of more than one hypothesis), in matching-cost units.
/// Tuned with [`DEFAULT_P1`].
pub const DEFAULT_P2: f32 = 2.0;

/// Default side of the median filter on the index map (the outlier study, `research/learned-costs.md`).
pub const DEFAULT_MEDIAN: usize = 5;

/// Which SGM paths are aggregated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Directions {
    /// Left, right, up, down.
    Four,
    /// The four above and the four diagonals.
    Eight,
}

impl Directions {
    /// Number of paths.
    pub fn count(self) -> usize {
        match self {
            Self::Four => 4,
            Self::Eight => 8,
        }
    }
}

/// Which hypotheses get a matching cost computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SweepStep {
    /// All `N` spheres.
    All,
    /// Spheres `n = 0, 2, ..., N-2` (half the warping and matching work); the
    /// cost of an odd hypothesis is the mean of its two neighbours' (the
    /// last one copies `N-2`), and SGM still runs over all `N`.
    EveryOther,
}

impl SweepStep {
    /// Hypotheses between two that get a matching cost: 1 or 2.
    pub fn stride(self) -> usize {
        match self {
            Self::All => 1,
            Self::EveryOther => 2,
        }
    }
}

/// Parameters of the ZNCC + SGM method.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SgmParams {
    /// Penalty for a change of one hypothesis between neighbours, in
    /// matching-cost units (`(1 - zncc) / 2` averaged over camera pairs).
    pub p1: f32,
    /// Penalty for larger changes, same units; `P2 >= P1`.
    pub p2: f32,
    /// Number of SGM paths.
    pub directions: Directions,
    /// Hypotheses that get a matching cost.
    pub sweep: SweepStep,
    /// Side of the square ZNCC patch, odd (9 in the paper).
    pub patch: usize,
    /// Side of the median filter applied to the index map after WTA (0 or 1: none).
    #[serde(default)]
    pub median: usize,
    /// Pixels whose confidence is below this get no answer (NaN; 0: every pixel answers).
    #[serde(default)]
    pub min_confidence: f32,
}

impl Default for SgmParams {
    fn default() -> Self {
        Self {
            p1: DEFAULT_P1,
            p2: DEFAULT_P2,
            directions: Directions::Eight,
            sweep: SweepStep::All,
            patch: 9,
            median: DEFAULT_MEDIAN,
            min_confidence: 0.0,
        }
    }
}

impl SgmParams {
    /// The largest `P2` that keeps the sum of all paths inside a `u16`.
    pub fn max_p2(directions: Directions) -> f32 {
        (f32::from(u16::MAX) / directions.count() as f32 - COST_SCALE) / COST_SCALE
    }

    /// Checks the penalties and the patch size.
    ///
    /// # Errors
    /// [`StereoError::Penalties`] for non-finite or negative values, `P2 < P1`
    /// or `P2` too large for 16-bit aggregation; [`StereoError::Parameter`] for
    /// an even or zero patch size, an even median filter size or a minimum confidence
    /// outside `[0, 1]`.
    pub fn validate(&self) -> Result<(), StereoError> {
        let bad = |reason: String| StereoError::Penalties {
            p1: self.p1,
            p2: self.p2,
            reason,
        };
        if !(self.p1.is_finite() && self.p2.is_finite()) || self.p1 < 0.0 || self.p2 < 0.0 {
            return Err(bad("expected finite non-negative penalties".into()));
        }
        if self.p2 < self.p1 {
            return Err(bad("expected P2 >= P1 (larger jumps cost more)".into()));
        }
        let max = Self::max_p2(self.directions);
        if self.p2 > max {
            return Err(bad(format!(
                "expected P2 <= {max:.2} with {} paths (matching costs are in [0, 1]; \
                 larger penalties overflow the 16-bit aggregation)",
                self.directions.count()
            )));
        }
        if !(self.min_confidence.is_finite() && (0.0..=1.0).contains(&self.min_confidence)) {
            return Err(StereoError::Parameter {
                name: "min_confidence",
                value: self.min_confidence.to_string(),
                expected: "a value in [0, 1]",
            });
        }
        if self.median > 1 && self.median.is_multiple_of(2) {
            return Err(StereoError::Parameter {
                name: "median",
                value: self.median.to_string(),
                expected: "an odd number of pixels (or 0: none)",
            });
        }
        if self.patch == 0 || self.patch.is_multiple_of(2) {
            return Err(StereoError::Parameter {
                name: "patch",
                value: self.patch.to_string(),
                expected: "an odd number of pixels (9 in the paper)",
            });
        }
        Ok(())
    }

    /// `P1` in fixed-point cost units.
    pub(crate) fn p1_units(&self) -> i16 {
        (self.p1 * COST_SCALE).round() as i16
    }

    /// `P2` in fixed-point cost units.
    pub(crate) fn p2_units(&self) -> i16 {
        (self.p2 * COST_SCALE).round() as i16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation() {
        assert!(SgmParams::default().validate().is_ok());
        let p = |p1, p2| SgmParams {
            p1,
            p2,
            ..SgmParams::default()
        };
        assert!(p(0.5, 0.1).validate().is_err());
        assert!(p(-0.1, 0.1).validate().is_err());
        assert!(p(0.1, f32::NAN).validate().is_err());
        assert!(p(0.1, 100.0).validate().is_err());
        assert!(p(0.1, 14.0).validate().is_ok());
        let even = SgmParams {
            patch: 8,
            ..SgmParams::default()
        };
        assert!(even.validate().is_err());
        for (median, min_confidence, ok) in [(4, 0.0, false), (5, 1.5, false), (0, 0.05, true)] {
            let p = SgmParams {
                median,
                min_confidence,
                ..SgmParams::default()
            };
            assert_eq!(
                p.validate().is_ok(),
                ok,
                "median {median}, {min_confidence}"
            );
        }
    }
}
