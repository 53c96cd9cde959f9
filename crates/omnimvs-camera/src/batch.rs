//! Shared by the batched projections (`project_many`), which give `project`'s results to the
//! bit: how many points go through a step together, and a cheap test of which side of a
//! field of view's edge a point lies, which skips the `atan2` of the exact test for every
//! point not near the edge.

/// Points per step of the batched projections: independent chains of multiplications and
/// divisions that overlap instead of waiting on one another.
pub(crate) const BATCH_LANES: usize = 8;

/// Points within this many radians of the edge (about; relative to their distance from the
/// centre) are left to the exact test. Far above the rounding of either test (1e-15).
const EDGE_MARGIN: f64 = 1e-6;

/// The cone of directions within `half_fov` of the optical axis.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FovCone {
    cos: f64,
    sin: f64,
    /// False when the test cannot be used (a half field of view outside `(0, pi)`).
    usable: bool,
}

impl FovCone {
    pub(crate) fn new(half_fov_rad: f64) -> Self {
        Self {
            cos: half_fov_rad.cos(),
            sin: half_fov_rad.sin(),
            usable: half_fov_rad > 0.0 && half_fov_rad < std::f64::consts::PI,
        }
    }

    /// Whether the direction at distance `rho >= 0` from the axis and `z` along it lies
    /// inside the cone (`Some(true)`) or outside (`Some(false)`), when it is at least about
    /// 1e-6 rad from the edge; `None` near the edge, at the origin or for NaN, where only the
    /// exact test (`atan2(rho, z) <= half_fov`) decides.
    ///
    /// Why it agrees with the exact test: `rho cos(h) - z sin(h) = |p| sin(alpha - h)` for
    /// the angle `alpha = atan2(rho, z)` in `[0, pi]`, whose sign is that of `alpha - h`;
    /// a magnitude above `1e-6 (rho + |z|)` puts `alpha` at least 1e-6 rad from `h`.
    #[inline(always)]
    pub(crate) fn side(&self, rho: f64, z: f64) -> Option<bool> {
        let s = rho * self.cos - z * self.sin;
        let margin = EDGE_MARGIN * (rho + z.abs());
        if !self.usable {
            None
        } else if s > margin {
            Some(false)
        } else if s < -margin {
            Some(true)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over a fine sweep of angles around several edges, a decided side always agrees with
    /// `atan2`, and only angles close to the edge are left undecided.
    #[test]
    fn decided_sides_agree_with_atan2() {
        for half_fov_deg in [30.0, 90.0, 97.5, 110.0, 125.0, 179.0] {
            let h = f64::to_radians(half_fov_deg);
            let cone = FovCone::new(h);
            let mut undecided = 0;
            for k in -20_000..=20_000 {
                let alpha = h + f64::from(k) * 1e-7 + f64::from(k).signum() * 1e-12;
                if !(0.0..=std::f64::consts::PI).contains(&alpha) {
                    continue;
                }
                for dist in [1e-3, 1.0, 7e4] {
                    let (rho, z) = (dist * alpha.sin(), dist * alpha.cos());
                    let exact = rho.atan2(z) <= h;
                    match cone.side(rho, z) {
                        Some(inside) => assert_eq!(inside, exact, "{half_fov_deg} {alpha}"),
                        None => undecided += 1,
                    }
                }
            }
            assert!(undecided < 3 * 60, "{half_fov_deg}: {undecided} undecided");
            // Far from the edge every point is decided.
            assert_eq!(cone.side(0.0, 1.0), Some(true));
            assert_eq!(cone.side(h.sin() * 0.5, 1.0), Some(true));
            assert_eq!(cone.side(0.0, 0.0), None);
            assert_eq!(cone.side(f64::NAN, 1.0), None);
        }
        assert_eq!(FovCone::new(std::f64::consts::PI).side(0.0, 1.0), None);
    }
}
