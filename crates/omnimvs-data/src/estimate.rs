//! The one interface of every depth method: [`DepthEstimator`] (the classical ZNCC + SGM and
//! every network implement it), its answer [`DepthEstimate`], per-stage timings through a
//! [`StageObserver`], and [`EstimateError`], which carries each implementation's own error.

use std::error::Error;
use std::fmt;

use omnimvs_core::GrayImage;
use omnimvs_sweep::SweepSpec;
use serde::ser::{Serialize, SerializeMap, Serializer};

/// One frame's depth on a sweep: every map is row-major on `spec.grid`.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthEstimate {
    /// The grid and the hypotheses the maps are on.
    pub spec: SweepSpec,
    /// Name of the method (`ZNCC+SGM`, `OmniMVS`, `cascade`).
    pub method: String,
    /// Inverse depth (1/m) of `index` under `spec.hypotheses`.
    pub inv_depth: Vec<f32>,
    /// Fractional hypothesis index `n_hat` in `[0, N - 1]`.
    pub index: Vec<f32>,
    /// Confidence in `[0, 1]` (the classical method's `1 - best/second-best cost`).
    pub confidence: Option<Vec<f32>>,
    /// Entropy (nats) of the per-pixel distribution over hypotheses across the whole range
    /// (the networks': the paper's over its spheres, the cascade's coarse stage's over its 32,
    /// resampled to the grid), higher where the answer is less sure.
    pub entropy: Option<Vec<f32>>,
    /// Standard deviation of that distribution in index units of `spec`'s hypotheses, where
    /// the method gives it (the cascade: its coarse stage's, resampled to the grid): how far
    /// off the answer may be, in the unit of the error figures times `N / 100`.
    pub spread: Option<Vec<f32>>,
    /// Wall time of the estimate, seconds.
    pub seconds: f64,
}

/// An uncertainty map of a [`DepthEstimate`] and a bound on it
/// ([`DepthEstimate::leave_uncertain`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Uncertainty {
    /// The entropy, nats.
    Entropy(f32),
    /// The spread (standard deviation), index units of the estimate's hypotheses.
    Spread(f32),
}

/// What may be done to an estimate after its method, as `omnimvs infer` and `omnimvs.infer`
/// offer it; [`Finishing::apply`] runs the steps in this order.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Finishing {
    /// [`DepthEstimate::snap_edges`] at this percentage of the `N` hypotheses, in (0, 100].
    pub snap_edges_pct: Option<f64>,
    /// [`DepthEstimate::leave_uncertain`] above this entropy (nats), 0 or more.
    pub max_entropy: Option<f32>,
    /// [`DepthEstimate::leave_uncertain`] above this spread (index units), 0 or more.
    pub max_spread: Option<f32>,
}

/// A [`Finishing`] option out of its range: the option (`name`, as `omnimvs.infer` calls it), the
/// value given and what it expects.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{value}: expected {expected}")]
pub struct FinishingError {
    pub name: &'static str,
    pub value: String,
    pub expected: &'static str,
}

impl Finishing {
    /// What `snap_edges_pct` expects.
    pub const SNAP_EDGES_EXPECTED: &'static str =
        "a percentage of the hypotheses in (0, 100], e.g. 8";
    /// What `max_entropy` expects.
    pub const MAX_ENTROPY_EXPECTED: &'static str = "an entropy in nats, 0 or more, e.g. 2.6";
    /// What `max_spread` expects.
    pub const MAX_SPREAD_EXPECTED: &'static str = "a spread in index units, 0 or more, e.g. 30";

    /// `pct` as a `snap_edges_pct`.
    ///
    /// # Errors
    /// [`FinishingError`] outside (0, 100].
    pub fn snap_edges_pct(pct: f64) -> Result<f64, FinishingError> {
        check(
            pct > 0.0 && pct <= 100.0,
            "snap_edges",
            pct,
            Self::SNAP_EDGES_EXPECTED,
        )
    }

    /// `nats` as a `max_entropy`.
    ///
    /// # Errors
    /// [`FinishingError`] for a negative or non-finite value.
    pub fn max_entropy(nats: f32) -> Result<f32, FinishingError> {
        let ok = nats.is_finite() && nats >= 0.0;
        check(ok, "max_entropy", nats, Self::MAX_ENTROPY_EXPECTED)
    }

    /// `units` as a `max_spread`.
    ///
    /// # Errors
    /// [`FinishingError`] for a negative or non-finite value.
    pub fn max_spread(units: f32) -> Result<f32, FinishingError> {
        let ok = units.is_finite() && units >= 0.0;
        check(ok, "max_spread", units, Self::MAX_SPREAD_EXPECTED)
    }

    /// Every option given, checked.
    ///
    /// # Errors
    /// [`FinishingError`] for the first option out of its range.
    pub fn checked(self) -> Result<Self, FinishingError> {
        self.snap_edges_pct.map(Self::snap_edges_pct).transpose()?;
        self.max_entropy.map(Self::max_entropy).transpose()?;
        self.max_spread.map(Self::max_spread).transpose()?;
        Ok(self)
    }

    /// Snaps the edges, then leaves the pixels above the entropy bound, then those above the
    /// spread bound, each when given.
    pub fn apply(&self, est: &mut DepthEstimate) {
        if let Some(pct) = self.snap_edges_pct {
            est.snap_edges(pct);
        }
        if let Some(nats) = self.max_entropy {
            est.leave_uncertain(Uncertainty::Entropy(nats));
        }
        if let Some(units) = self.max_spread {
            est.leave_uncertain(Uncertainty::Spread(units));
        }
    }
}

/// `value` when `ok`, else the [`FinishingError`] of option `name`.
fn check<T: fmt::Display>(
    ok: bool,
    name: &'static str,
    value: T,
    expected: &'static str,
) -> Result<T, FinishingError> {
    if ok {
        Ok(value)
    } else {
        Err(FinishingError {
            name,
            value: value.to_string(),
            expected,
        })
    }
}

impl DepthEstimate {
    /// A network's estimate: `index` and its `entropy` on `spec`, the inverse depth computed
    /// from the hypotheses, in `seconds`.
    pub fn with_entropy(
        spec: SweepSpec,
        method: impl Into<String>,
        index: Vec<f32>,
        entropy: Vec<f32>,
        seconds: f64,
    ) -> Self {
        Self {
            entropy: Some(entropy),
            seconds,
            ..Self::from_index(spec, method, index)
        }
    }

    /// Moves answers that lie between the two surfaces of a depth edge onto the nearer of them
    /// ([`crate::edges::snap_edges`]): where a pixel's 3x3 neighbourhood spans more than
    /// `threshold_pct` percent of the `N` hypotheses (the unit of the paper's error figures),
    /// it takes the neighbourhood's minimum or maximum index. The inverse depth follows the
    /// index; entropy and confidence stay the method's. Returns how many pixels moved.
    pub fn snap_edges(&mut self, threshold_pct: f64) -> usize {
        let threshold = (threshold_pct / 100.0 * self.spec.ndepth() as f64) as f32;
        let (h, w) = (self.spec.height(), self.spec.width());
        let moved = crate::edges::snap_edges(&mut self.index, h, w, threshold);
        if moved > 0 {
            self.inv_depth = self.spec.inv_depth_of(&self.index);
        }
        moved
    }

    /// Leaves the pixels whose uncertainty is above a bound (`above`: by the entropy or by the
    /// spread) without an answer: NaN index and inverse depth, as ZNCC+SGM's `min_confidence`
    /// does (the metrics then score the others and report their share as coverage; a point
    /// cloud leaves them out). Returns how many pixels it left; none for an estimate without
    /// that map.
    pub fn leave_uncertain(&mut self, above: Uncertainty) -> usize {
        let (map, bound) = match above {
            Uncertainty::Entropy(nats) => (&self.entropy, nats),
            Uncertainty::Spread(units) => (&self.spread, units),
        };
        let Some(map) = map else {
            return 0;
        };
        let mut left = 0;
        for ((index, inv), &u) in self.index.iter_mut().zip(&mut self.inv_depth).zip(map) {
            if u > bound && !index.is_nan() {
                *index = f32::NAN;
                *inv = f32::NAN;
                left += 1;
            }
        }
        left
    }

    /// An estimate of `index` on `spec`, its inverse depth computed from the hypotheses.
    pub fn from_index(spec: SweepSpec, method: impl Into<String>, index: Vec<f32>) -> Self {
        Self {
            inv_depth: spec.inv_depth_of(&index),
            spec,
            method: method.into(),
            index,
            confidence: None,
            entropy: None,
            spread: None,
            seconds: 0.0,
        }
    }
}

/// Receives the wall time of each stage of an estimate. Measuring a stage can cost time (a
/// network waits for its device after each), so an estimator measures only when
/// [`Self::wants_timings`] says so.
pub trait StageObserver {
    /// Whether stages are to be measured.
    fn wants_timings(&self) -> bool {
        true
    }

    /// One stage took `seconds` (in the order they run; `total` last).
    fn stage(&mut self, name: &'static str, seconds: f64);

    /// Several stages in order, given only when [`Self::wants_timings`].
    fn stages(&mut self, stages: &[(&'static str, f64)]) {
        if self.wants_timings() {
            for &(name, seconds) in stages {
                self.stage(name, seconds);
            }
        }
    }
}

/// The observer that measures nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoTimings;

impl StageObserver for NoTimings {
    fn wants_timings(&self) -> bool {
        false
    }

    fn stage(&mut self, _name: &'static str, _seconds: f64) {}
}

/// An observer that keeps the stages in order; serialised as `{"<stage>_s": seconds, ...}`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageTimes {
    /// `(stage, seconds)` in the order the stages ran.
    pub stages: Vec<(&'static str, f64)>,
}

impl StageTimes {
    /// The seconds of `name` (0 when it was not reported).
    pub fn get(&self, name: &str) -> f64 {
        self.stages
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(0.0, |(_, s)| *s)
    }
}

impl StageObserver for StageTimes {
    fn stage(&mut self, name: &'static str, seconds: f64) {
        self.stages.push((name, seconds));
    }
}

impl Serialize for StageTimes {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.stages.len()))?;
        for (name, seconds) in &self.stages {
            map.serialize_entry(&format!("{name}_s"), seconds)?;
        }
        map.end()
    }
}

/// A depth method prepared for one rig and one sweep (its tables are built once): the
/// frame's gray images (rig order, any intensity range) in, a [`DepthEstimate`] on
/// [`Self::spec`] out.
pub trait DepthEstimator {
    /// Name of the method.
    fn name(&self) -> &str;

    /// The grid and hypotheses the estimates are on.
    fn spec(&self) -> &SweepSpec;

    /// The estimate of one frame, each stage's time given to `observer` when it wants them.
    ///
    /// # Errors
    /// The implementation's error (wrong number or size of images, a failing device).
    fn estimate_observed(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
    ) -> Result<DepthEstimate, EstimateError>;

    /// The estimate of one frame, stages not measured.
    ///
    /// # Errors
    /// As [`Self::estimate_observed`].
    fn estimate(&self, images: &[GrayImage]) -> Result<DepthEstimate, EstimateError> {
        self.estimate_observed(images, &mut NoTimings)
    }
}

/// The error of an estimator: the implementation's own error, whose message it shows and
/// which [`Self::downcast_ref`] gives back.
#[derive(Debug)]
pub struct EstimateError(Box<dyn Error + Send + Sync + 'static>);

impl EstimateError {
    /// Wraps an implementation's error.
    pub fn new(error: impl Error + Send + Sync + 'static) -> Self {
        Self(Box::new(error))
    }

    /// The implementation's error as `E`, if it is one.
    pub fn downcast_ref<E: Error + 'static>(&self) -> Option<&E> {
        self.0.downcast_ref()
    }
}

impl fmt::Display for EstimateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl Error for EstimateError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        Some(&*self.0)
    }
}

impl From<crate::DataError> for EstimateError {
    fn from(e: crate::DataError) -> Self {
        Self::new(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_times_serialise_in_order_with_units() {
        let mut t = StageTimes::default();
        t.stage("warp", 1.5);
        t.stage("total", 2.0);
        assert_eq!(
            serde_json::to_string(&t).unwrap(),
            r#"{"warp_s":1.5,"total_s":2.0}"#
        );
        assert_eq!(t.get("total"), 2.0);
        assert_eq!(t.get("cost"), 0.0);
        assert!(!NoTimings.wants_timings());
    }

    fn estimate(index: Vec<f32>, entropy: Option<Vec<f32>>) -> DepthEstimate {
        let spec = SweepSpec::from_sizes(2, index.len() / 2, 45.0, 192, 0.5).unwrap();
        DepthEstimate {
            entropy,
            ..DepthEstimate::from_index(spec, "test", index)
        }
    }

    #[test]
    fn uncertain_pixels_are_left_without_an_answer() {
        let mut est = estimate(vec![10.0, 20.0, 30.0, 40.0], Some(vec![0.5, 2.5, 2.0, 3.0]));
        // No spread map: nothing to leave by it.
        assert_eq!(est.leave_uncertain(Uncertainty::Spread(0.0)), 0);
        assert_eq!(est.leave_uncertain(Uncertainty::Entropy(2.0)), 2);
        assert_eq!(est.index[0], 10.0);
        assert_eq!(est.index[2], 30.0);
        assert!(est.index[1].is_nan() && est.inv_depth[1].is_nan());
        assert!(est.index[3].is_nan() && est.inv_depth[3].is_nan());
        assert_eq!(est.inv_depth[0], est.spec.inv_depth_of(&[10.0])[0]);
        // Already left pixels are not counted twice; no entropy, nothing to leave.
        assert_eq!(est.leave_uncertain(Uncertainty::Entropy(2.0)), 0);
        let mut plain = estimate(vec![10.0, 20.0, 30.0, 40.0], None);
        assert_eq!(plain.leave_uncertain(Uncertainty::Entropy(0.0)), 0);
        assert!(plain.index.iter().all(|v| v.is_finite()));
        // By the spread: index units.
        let mut spread = DepthEstimate {
            spread: Some(vec![1.0, 12.0, 30.0, 8.0]),
            ..estimate(vec![10.0, 20.0, 30.0, 40.0], None)
        };
        assert_eq!(spread.leave_uncertain(Uncertainty::Spread(10.0)), 2);
        assert!(spread.index[1].is_nan() && spread.index[2].is_nan());
        assert_eq!((spread.index[0], spread.index[3]), (10.0, 40.0));
    }

    #[test]
    fn finishing_checks_its_options_and_applies_them_in_order() {
        let ok = Finishing {
            snap_edges_pct: Some(8.0),
            max_entropy: Some(2.0),
            max_spread: None,
        };
        assert_eq!(ok.checked(), Ok(ok));
        for (bad, name) in [
            (
                Finishing {
                    snap_edges_pct: Some(0.0),
                    ..ok
                },
                "snap_edges",
            ),
            (
                Finishing {
                    max_entropy: Some(f32::NAN),
                    ..ok
                },
                "max_entropy",
            ),
            (
                Finishing {
                    max_spread: Some(-1.0),
                    ..ok
                },
                "max_spread",
            ),
        ] {
            let err = bad.checked().unwrap_err();
            assert_eq!(err.name, name);
            assert!(err.to_string().contains("expected"), "{err}");
        }
        // The edge 60 of the step 150 | 60 | 20 snaps to 20 first; then only the pixel whose
        // entropy is above 2 is left.
        let mut est = estimate(
            vec![150.0, 60.0, 20.0, 20.0],
            Some(vec![0.5, 1.0, 3.0, 0.5]),
        );
        ok.apply(&mut est);
        assert_eq!(
            (est.index[0], est.index[1], est.index[3]),
            (150.0, 20.0, 20.0)
        );
        assert!(est.index[2].is_nan());
    }

    #[test]
    fn errors_keep_the_implementation_error() {
        let e = EstimateError::new(crate::DataError::mismatch("images", 4, 3));
        assert!(e.downcast_ref::<crate::DataError>().is_some());
        assert_eq!(e.to_string(), "images: expected 4, found 3");
        assert!(e.source().is_some());
    }
}
