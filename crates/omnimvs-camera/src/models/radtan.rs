//! OpenCV's radial-tangential ("radtan", Brown-Conrady) distortion of
//! normalised image coordinates, and its iterative inverse.

use nalgebra::{Matrix2, Vector2};

/// Most Gauss-Newton steps [`RadTan::undistort`] takes.
const UNDISTORT_MAX_ITERATIONS: usize = 100;

/// Residual, relative to `1 + |m_distorted|`, at which the inverse has
/// converged (well below 1e-12).
const UNDISTORT_TOLERANCE: f64 = 1e-13;

/// Radial-tangential distortion coefficients as OpenCV and Kalibr name them:
/// with `r^2 = x^2 + y^2` of the undistorted normalised point `(x, y)`,
///
/// * `x'' = x (1 + k1 r^2 + k2 r^4) + 2 p1 x y + p2 (r^2 + 2 x^2)`,
/// * `y'' = y (1 + k1 r^2 + k2 r^4) + p1 (r^2 + 2 y^2) + 2 p2 x y`.
///
/// The map is used only where it is locally invertible and the radial part
/// `r (1 + k1 r^2 + k2 r^4)` still increases (see [`Self::is_valid`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RadTan {
    pub(crate) k1: f64,
    pub(crate) k2: f64,
    pub(crate) p1: f64,
    pub(crate) p2: f64,
}

impl RadTan {
    /// The largest `r^2` (exclusive) up to which the radial part
    /// `r (1 + k1 r^2 + k2 r^4)` increases: the smallest positive root `s`
    /// of `1 + 3 k1 s + 5 k2 s^2`, or infinity if there is none.
    pub(crate) fn max_r2(&self) -> f64 {
        let (a, b) = (5.0 * self.k2, 3.0 * self.k1);
        if a == 0.0 {
            return if b < 0.0 { -1.0 / b } else { f64::INFINITY };
        }
        let disc = b * b - 4.0 * a;
        if disc < 0.0 {
            return f64::INFINITY;
        }
        let sq = disc.sqrt();
        [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)]
            .into_iter()
            .filter(|s| *s > 0.0)
            .fold(f64::INFINITY, f64::min)
    }

    /// The distorted normalised point of an undistorted one.
    pub(crate) fn distort(&self, m: Vector2<f64>) -> Vector2<f64> {
        let (x, y) = (m.x, m.y);
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * self.k2);
        Vector2::new(
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// The Jacobian of [`Self::distort`] at `m`.
    fn jacobian(&self, m: Vector2<f64>) -> Matrix2<f64> {
        let (x, y) = (m.x, m.y);
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * self.k2);
        // d radial / d x = 2 x g, d radial / d y = 2 y g.
        let g = self.k1 + 2.0 * self.k2 * r2;
        let dxx = radial + 2.0 * x * x * g + 2.0 * self.p1 * y + 6.0 * self.p2 * x;
        let dxy = 2.0 * x * y * g + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
        let dyy = radial + 2.0 * y * y * g + 6.0 * self.p1 * y + 2.0 * self.p2 * x;
        Matrix2::new(dxx, dxy, dxy, dyy)
    }

    /// Whether the undistorted point `m` lies where the distortion is used:
    /// `|m|^2 < max_r2()` and the Jacobian has a positive determinant.
    pub(crate) fn is_valid(&self, m: Vector2<f64>) -> bool {
        m.norm_squared() < self.max_r2() && self.jacobian(m).determinant() > 0.0
    }

    /// The undistorted normalised point whose distortion is `m_distorted`,
    /// by Gauss-Newton iteration from `m_distorted`. `None` if it does not
    /// converge within 100 steps (far from the centre strong
    /// distortion needs many) or converges outside [`Self::is_valid`].
    pub(crate) fn undistort(&self, m_distorted: Vector2<f64>) -> Option<Vector2<f64>> {
        let tolerance = UNDISTORT_TOLERANCE * (1.0 + m_distorted.norm());
        let mut m = m_distorted;
        for _ in 0..UNDISTORT_MAX_ITERATIONS {
            let residual = self.distort(m) - m_distorted;
            if !residual.iter().all(|v| v.is_finite()) {
                return None;
            }
            if residual.amax() <= tolerance {
                return self.is_valid(m).then_some(m);
            }
            let step = self.jacobian(m).try_inverse()? * residual;
            m -= step;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const STRONG: RadTan = RadTan {
        k1: -0.28,
        k2: 0.07,
        p1: 0.0002,
        p2: -0.0003,
    };

    #[test]
    fn zero_coefficients_are_the_identity() {
        let none = RadTan {
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
        };
        let m = Vector2::new(0.3, -1.7);
        assert_eq!(none.distort(m), m);
        assert_eq!(none.undistort(m), Some(m));
        assert_eq!(none.max_r2(), f64::INFINITY);
    }

    #[test]
    fn distortion_by_hand() {
        // m = (0.5, -0.25): r^2 = 0.3125, radial = 1 - 0.28 * 0.3125
        // + 0.07 * 0.09765625 = 0.9193359375;
        // x'' = 0.5 * 0.9193359375 + 2 * 0.0002 * (-0.125) - 0.0003 * (0.3125 + 0.5)
        //     = 0.45966796875 - 0.00005 - 0.00024375 = 0.45937421875,
        // y'' = -0.25 * 0.9193359375 + 0.0002 * (0.3125 + 0.125) - 2 * 0.0003 * (-0.125)
        //     = -0.229833984375 + 0.0000875 + 0.000075 = -0.229671484375.
        let d = STRONG.distort(Vector2::new(0.5, -0.25));
        assert!((d.x - 0.45937421875).abs() < 1e-15);
        assert!((d.y + 0.229671484375).abs() < 1e-15);
    }

    #[test]
    fn undistort_inverts_distort_inside_the_monotonic_radius() {
        // 1 + 3 k1 s + 5 k2 s^2 = 1 - 0.84 s + 0.35 s^2 has no real root.
        assert_eq!(STRONG.max_r2(), f64::INFINITY);
        let barrel = RadTan { k2: 0.0, ..STRONG };
        let max_r2 = barrel.max_r2();
        assert!((max_r2 - 1.0 / 0.84).abs() < 1e-15);
        for model in [STRONG, barrel] {
            for i in 0..40 {
                for j in 0..40 {
                    let m = Vector2::new(-1.0 + 0.05 * f64::from(i), -1.0 + 0.05 * f64::from(j));
                    if !model.is_valid(m) {
                        continue;
                    }
                    let distorted = model.distort(m);
                    let back = model.undistort(distorted).unwrap();
                    // Near the monotonic radius the inverse is ill-conditioned:
                    // the residual is tiny, the point itself a little less exact.
                    assert!((model.distort(back) - distorted).amax() < 1e-12, "{m:?}");
                    assert!((back - m).amax() < 1e-9, "{m:?} {back:?}");
                }
            }
        }
        // Beyond the monotonic radius the distorted point is not unique.
        let outside = Vector2::new(1.2, 0.0);
        assert!(!barrel.is_valid(outside));
    }
}
