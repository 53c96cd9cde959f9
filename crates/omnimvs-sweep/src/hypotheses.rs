use crate::SweepError;

/// `N` inverse-depth hypotheses (spheres) evenly spaced from
/// `d_0 = 1/max_depth` to `d_(N-1) = 1/min_depth`, in 1/m.
///
/// Like the reference implementation, `max_depth = 1/f64::EPSILON`, so `d_0`
/// is `f64::EPSILON` (the sphere at infinity) rather than exactly 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvDepthHypotheses {
    /// Number of hypotheses `N`.
    pub count: usize,
    /// Minimum depth in metres (`config.omnimvs_sweep_min_depth`).
    pub min_depth_m: f64,
}

impl InvDepthHypotheses {
    /// # Errors
    /// [`SweepError::Hypotheses`] when `count < 2` or the depth is not a
    /// positive finite number.
    pub fn new(count: usize, min_depth_m: f64) -> Result<Self, SweepError> {
        if count < 2 {
            return Err(SweepError::Hypotheses(format!(
                "ndepth {count}: expected at least 2 spheres"
            )));
        }
        if !(min_depth_m.is_finite() && min_depth_m > 0.0) {
            return Err(SweepError::Hypotheses(format!(
                "min depth {min_depth_m} m: expected a positive number of metres"
            )));
        }
        Ok(Self { count, min_depth_m })
    }

    /// `d_0`, the smallest inverse depth (1/m).
    pub fn min_inv_depth(&self) -> f64 {
        f64::EPSILON
    }

    /// `d_(N-1) = 1/min_depth` (1/m).
    pub fn max_inv_depth(&self) -> f64 {
        1.0 / self.min_depth_m
    }

    /// Spacing between consecutive hypotheses (1/m).
    pub fn step(&self) -> f64 {
        (self.max_inv_depth() - self.min_inv_depth()) / (self.count as f64 - 1.0)
    }

    /// Inverse depth (1/m) of a fractional index `n`.
    pub fn inv_depth(&self, index: f64) -> f64 {
        self.min_inv_depth() + index * self.step()
    }

    /// Fractional index `n = (N-1)(d - d_0)/(d_(N-1) - d_0)` of an inverse
    /// depth (1/m).
    pub fn index(&self, inv_depth: f64) -> f64 {
        (inv_depth - self.min_inv_depth()) / self.step()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_round_trip() {
        let h = InvDepthHypotheses::new(192, 0.5).unwrap();
        assert!((h.inv_depth(0.0) - f64::EPSILON).abs() < 1e-30);
        assert!((h.inv_depth(191.0) - 2.0).abs() < 1e-12);
        for n in [0.0, 1.5, 95.25, 191.0] {
            assert!((h.index(h.inv_depth(n)) - n).abs() < 1e-9);
        }
    }

    #[test]
    fn rejects_bad_input() {
        assert!(InvDepthHypotheses::new(1, 0.5).is_err());
        assert!(InvDepthHypotheses::new(192, 0.0).is_err());
        assert!(InvDepthHypotheses::new(192, f64::NAN).is_err());
    }
}
