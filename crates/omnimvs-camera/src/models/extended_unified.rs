use nalgebra::Vector3;

use super::{Focal, check_finite, check_range};
use crate::{CameraError, Pixel};

const MODEL: &str = "eucm";

/// The extended unified camera model (EUCM) of Khomutenko, Garcia and
/// Martinet, "An Enhanced Unified Camera Model", IEEE RA-L 2016 (Basalt's
/// `eucm`): the unified model with the unit sphere replaced by an ellipsoid.
///
/// * `d = sqrt(beta (x^2 + y^2) + z^2)`,
/// * `col = fx x / (alpha d + (1 - alpha) z) + cx`, likewise `row` with `fy`,
///   `y`, `cy`.
///
/// Valid points are those with `z > -w d`, `w = alpha / (1 - alpha)` if
/// `alpha <= 0.5`, else `(1 - alpha) / alpha`. For `alpha <= 0.5` this is
/// exactly where the denominator `alpha d + (1 - alpha) z` is positive; for
/// `alpha > 0.5` the denominator stays positive a little further, but the
/// image radius `|m|` reaches its largest value `1 / sqrt(beta (2 alpha - 1))`
/// on the cone `z = -w d` and decreases beyond it, so the projection is
/// one-to-one only inside the cone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtendedUnified {
    focal: Focal,
    alpha: f64,
    beta: f64,
}

impl ExtendedUnified {
    /// An extended unified camera from its calibration: focal lengths `fx`,
    /// `fy` and principal point `cx`, `cy` in pixels (0-based), `alpha` in
    /// `[0, 1]` and `beta > 0`.
    ///
    /// # Errors
    ///
    /// [`CameraError::Param`] naming the first parameter that is not finite,
    /// a focal length or `beta` that is not positive, or `alpha` outside
    /// `[0, 1]`.
    pub fn new(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        alpha: f64,
        beta: f64,
    ) -> Result<Self, CameraError> {
        let model = Self {
            focal: Focal::new(MODEL, fx, fy, cx, cy)?,
            alpha: check_range(MODEL, "alpha", alpha, 0.0, 1.0)?,
            beta: check_finite(MODEL, "beta", beta)?,
        };
        if beta <= 0.0 {
            return Err(CameraError::param(
                MODEL,
                "beta",
                format!("must be positive, got {beta}"),
            ));
        }
        Ok(model)
    }

    /// Focal lengths and principal point, pixels.
    pub fn focal(&self) -> Focal {
        self.focal
    }

    /// The same model with other focal lengths and principal point.
    pub(crate) fn with_focal(&self, focal: Focal) -> Self {
        let mut model = *self;
        model.focal = focal;
        model
    }

    /// Weight of the ellipsoid projection against the pinhole.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Shape of the ellipsoid (1 for a sphere, the unified model).
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// `w` of the validity condition `z > -w d`.
    fn w(&self) -> f64 {
        if self.alpha <= 0.5 {
            self.alpha / (1.0 - self.alpha)
        } else {
            (1.0 - self.alpha) / self.alpha
        }
    }

    /// Whether a point of the camera frame lies in the valid domain
    /// `z > -w d` (see the type's documentation); the origin does not.
    pub fn is_valid_point(&self, p_cam: &Vector3<f64>) -> bool {
        let (x, y, z) = (p_cam.x, p_cam.y, p_cam.z);
        let d = (self.beta * (x * x + y * y) + z * z).sqrt();
        d > 0.0 && z > -self.w() * d
    }

    /// The full field of view, degrees. On the boundary `z = -w d` of a unit
    /// ray at angle `theta` from the axis, `tan^2 theta = (1 - w^2) / (w^2 beta)`
    /// with `cos theta <= 0`, so `theta = 90° + atan(w sqrt(beta) / sqrt(1 - w^2))`.
    pub fn max_fov_deg(&self) -> f64 {
        let w = self.w();
        let half = std::f64::consts::FRAC_PI_2 + (w * self.beta.sqrt()).atan2((1.0 - w * w).sqrt());
        2.0 * half.to_degrees()
    }

    /// Projects a point of the camera frame to a pixel; `None` outside the
    /// valid domain ([`Self::is_valid_point`]).
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        if !self.is_valid_point(p_cam) {
            return None;
        }
        let (x, y, z) = (p_cam.x, p_cam.y, p_cam.z);
        let d = (self.beta * (x * x + y * y) + z * z).sqrt();
        let denom = self.alpha * d + (1.0 - self.alpha) * z;
        if denom <= 0.0 {
            return None;
        }
        Some(self.focal.pixel(x / denom, y / denom))
    }

    /// The unit ray (camera frame) of a pixel. `None` where
    /// `r^2 = mx^2 + my^2` exceeds `1 / (beta (2 alpha - 1))` for
    /// `alpha > 0.5` (`mx = (col - cx) / fx`, `my = (row - cy) / fy`), or
    /// where the ray falls outside the valid domain of [`Self::project`].
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        let (mx, my) = self.focal.plane(px);
        let r2 = mx * mx + my * my;
        let (alpha, beta) = (self.alpha, self.beta);
        if alpha > 0.5 && r2 > 1.0 / (beta * (2.0 * alpha - 1.0)) {
            return None;
        }
        let mz = (1.0 - beta * alpha * alpha * r2)
            / (alpha * (1.0 - (2.0 * alpha - 1.0) * beta * r2).sqrt() + (1.0 - alpha));
        let ray = Vector3::new(mx, my, mz).try_normalize(0.0)?;
        (ray.iter().all(|v| v.is_finite()) && self.is_valid_point(&ray)).then_some(ray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::test_support::{check_round_trips, pixel_grid, rays_up_to};

    /// Basalt's TUM VI 512x512 EUCM test camera.
    fn tumvi() -> ExtendedUnified {
        ExtendedUnified::new(
            191.14799816648748,
            191.13150946585135,
            254.95857715233118,
            256.8815466235898,
            0.6291060871161842,
            1.0418067403139693,
        )
        .unwrap()
    }

    #[test]
    fn golden_projection_by_hand() {
        // p = (1, -2, 3): d = sqrt(beta * 5 + 9) = 3.7694871934481813,
        // denom = alpha d + (1 - alpha) 3 = 3.4840890773561996,
        // col = fx / denom + cx = 309.82169744646976,
        // row = -2 fy / denom + cy = 147.16477117829265.
        let px = tumvi().project(&Vector3::new(1.0, -2.0, 3.0)).unwrap();
        assert!((px.col - 309.821_697_446_469_8).abs() < 1e-9, "{px:?}");
        assert!((px.row - 147.16477117829265).abs() < 1e-9, "{px:?}");
    }

    #[test]
    fn round_trips() {
        let cams = [
            tumvi(),
            // Basalt's EuRoC EUCM test camera.
            ExtendedUnified::new(
                460.76484651566468,
                459.4051018049483,
                365.8937161309615,
                249.33499869752445,
                0.5903365915227143,
                1.127468196965374,
            )
            .unwrap(),
            ExtendedUnified::new(300.0, 310.0, 500.0, 490.0, 0.4, 0.8).unwrap(),
            ExtendedUnified::new(300.0, 310.0, 500.0, 490.0, 0.0, 1.0).unwrap(),
            ExtendedUnified::new(300.0, 310.0, 500.0, 490.0, 0.9, 2.0).unwrap(),
        ];
        for cam in cams {
            let half_fov = cam.max_fov_deg().to_radians() / 2.0;
            let rays = rays_up_to(half_fov - 1e-6, 200);
            let n = check_round_trips(
                |p| cam.project(p),
                |px| cam.unproject(px),
                &pixel_grid(1000, 1000, 7),
                &rays,
            );
            assert!(n > 1000, "{cam:?}: only {n} pixels unproject");
        }
    }

    #[test]
    fn points_beyond_the_validity_cone_do_not_project() {
        let cam = tumvi();
        // w = (1 - alpha) / alpha = 0.5895570246092986:
        // 2 (90° + atan(w sqrt(beta) / sqrt(1 - w^2))) = 253.37 degrees.
        assert!((cam.max_fov_deg() - 253.37205163100572).abs() < 1e-9);
        let half = cam.max_fov_deg().to_radians() / 2.0;
        let inside = Vector3::new(0.0, (half - 1e-3).sin(), (half - 1e-3).cos());
        let outside = Vector3::new(0.0, (half + 1e-3).sin(), (half + 1e-3).cos());
        assert!(cam.project(&inside).is_some());
        assert!(cam.project(&outside).is_none());
        assert!(cam.project(&Vector3::new(0.0, 0.0, -1.0)).is_none());
        // A pinhole (alpha = 0) sees only z > 0.
        let pinhole = ExtendedUnified::new(300.0, 300.0, 0.0, 0.0, 0.0, 1.0).unwrap();
        assert!((pinhole.max_fov_deg() - 180.0).abs() < 1e-12);
        assert!(pinhole.project(&Vector3::new(1.0, 0.0, -0.01)).is_none());
    }

    #[test]
    fn invalid_parameters_are_named() {
        let cases = [
            (ExtendedUnified::new(-1.0, 1.0, 0.0, 0.0, 0.5, 1.0), "fx"),
            (ExtendedUnified::new(1.0, 0.0, 0.0, 0.0, 0.5, 1.0), "fy"),
            (ExtendedUnified::new(1.0, 1.0, 0.0, 0.0, 1.5, 1.0), "alpha"),
            (ExtendedUnified::new(1.0, 1.0, 0.0, 0.0, 0.5, 0.0), "beta"),
            (ExtendedUnified::new(1.0, 1.0, 0.0, 0.0, 0.5, -2.0), "beta"),
            (
                ExtendedUnified::new(1.0, 1.0, 0.0, 0.0, 0.5, f64::NAN),
                "beta",
            ),
        ];
        for (result, name) in cases {
            match result {
                Err(CameraError::Param { model, param, .. }) => {
                    assert_eq!((model, param), ("eucm", name));
                }
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
