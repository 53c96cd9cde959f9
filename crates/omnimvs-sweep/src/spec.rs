use crate::{EquirectGrid, InvDepthHypotheses, SweepError};

/// What a depth estimate answers on: the equirectangular output grid (`height x width`,
/// latitudes `±phi_deg`) and the `N` inverse-depth hypotheses its indices count. Every place
/// that sets up a sweep (the classical method, the networks, lookup tables, evaluation,
/// ground truth on a grid) builds one of these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepSpec {
    /// The output grid, rig frame.
    pub grid: EquirectGrid,
    /// The hypotheses of the index maps (1/m).
    pub hypotheses: InvDepthHypotheses,
}

impl SweepSpec {
    /// A grid and its hypotheses.
    pub fn new(grid: EquirectGrid, hypotheses: InvDepthHypotheses) -> Self {
        Self { grid, hypotheses }
    }

    /// `height x width` over `±phi_deg`, `ndepth` spheres from `min_depth_m` to infinity.
    ///
    /// # Errors
    /// [`SweepError::Grid`] or [`SweepError::Hypotheses`] for values out of range.
    pub fn from_sizes(
        height: usize,
        width: usize,
        phi_deg: f64,
        ndepth: usize,
        min_depth_m: f64,
    ) -> Result<Self, SweepError> {
        Ok(Self {
            grid: EquirectGrid::new(height, width, phi_deg)?,
            hypotheses: InvDepthHypotheses::new(ndepth, min_depth_m)?,
        })
    }

    /// Rows of the grid.
    pub fn height(&self) -> usize {
        self.grid.height
    }

    /// Columns of the grid.
    pub fn width(&self) -> usize {
        self.grid.width
    }

    /// Number of hypotheses `N`.
    pub fn ndepth(&self) -> usize {
        self.hypotheses.count
    }

    /// Inverse depth (1/m) of every (fractional) index of a map.
    pub fn inv_depth_of(&self, index: &[f32]) -> Vec<f32> {
        index
            .iter()
            .map(|&n| self.hypotheses.inv_depth(f64::from(n)) as f32)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_inverse_depths() {
        let spec = SweepSpec::from_sizes(160, 640, 45.0, 192, 0.5).unwrap();
        assert_eq!(
            (spec.height(), spec.width(), spec.ndepth()),
            (160, 640, 192)
        );
        let inv = spec.inv_depth_of(&[0.0, 191.0]);
        assert!((inv[1] - 2.0).abs() < 1e-6 && inv[0] < 1e-12);
        assert!(SweepSpec::from_sizes(1, 640, 45.0, 192, 0.5).is_err());
        assert!(SweepSpec::from_sizes(160, 640, 45.0, 1, 0.5).is_err());
    }
}
