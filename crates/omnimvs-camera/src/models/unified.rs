use nalgebra::{Vector2, Vector3};

use super::radtan::RadTan;
use super::{Focal, check_finite};
use crate::{CameraError, Pixel};

const MODEL: &str = "omni";

/// The unified camera model (UCM) of Mei and Rives, "Single View Point
/// Omnidirectional Camera Calibration from Planar Grids", ICRA 2007, with the
/// radial-tangential distortion of Kalibr's `omni` + `radtan`.
///
/// A point `p = (x, y, z)` is projected onto the unit sphere and then by a
/// pinhole shifted by `xi` behind the sphere's centre:
///
/// * `m = (x, y) / (z + xi |p|)` (normalised coordinates),
/// * `m'' = radtan(m)` with `k1, k2, p1, p2` (see [`PinholeRadtan`](super::PinholeRadtan)),
/// * `col = fx m''.x + cx`, `row = fy m''.y + cy`.
///
/// Valid points: for `xi <= 1`, `z > -xi |p|` (the denominator is positive);
/// for `xi > 1` the stricter `z > -|p| / xi`, where the image radius
/// `|m| = sin(theta) / (cos(theta) + xi)` reaches its largest value
/// `1 / sqrt(xi^2 - 1)` (its derivative is `(1 + xi cos(theta)) / (..)^2`)
/// and beyond which the projection folds back. With distortion, `m` must also
/// lie where the distortion is one-to-one: `|m|^2` below the first root of
/// `1 + 3 k1 r^2 + 5 k2 r^4` and a positive Jacobian determinant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unified {
    focal: Focal,
    xi: f64,
    distortion: RadTan,
}

impl Unified {
    /// A unified camera without distortion: focal lengths `fx`, `fy` and
    /// principal point `cx`, `cy` in pixels (0-based), mirror parameter
    /// `xi >= 0`.
    ///
    /// # Errors
    ///
    /// [`CameraError::Param`] naming the first parameter that is not finite,
    /// a focal length that is not positive, or a negative `xi`.
    pub fn new(fx: f64, fy: f64, cx: f64, cy: f64, xi: f64) -> Result<Self, CameraError> {
        Self::with_radtan(fx, fy, cx, cy, xi, [0.0; 4])
    }

    /// A unified camera with radial-tangential distortion
    /// `[k1, k2, p1, p2]` (Kalibr's `distortion_coeffs` for `radtan`).
    ///
    /// # Errors
    ///
    /// As [`Self::new`], and for a distortion coefficient that is not finite.
    pub fn with_radtan(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        xi: f64,
        [k1, k2, p1, p2]: [f64; 4],
    ) -> Result<Self, CameraError> {
        let model = Self {
            focal: Focal::new(MODEL, fx, fy, cx, cy)?,
            xi: check_finite(MODEL, "xi", xi)?,
            distortion: RadTan {
                k1: check_finite(MODEL, "k1", k1)?,
                k2: check_finite(MODEL, "k2", k2)?,
                p1: check_finite(MODEL, "p1", p1)?,
                p2: check_finite(MODEL, "p2", p2)?,
            },
        };
        if xi < 0.0 {
            return Err(CameraError::param(
                MODEL,
                "xi",
                format!("must not be negative, got {xi}"),
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

    /// Distance of the projection centre behind the unit sphere's centre.
    pub fn xi(&self) -> f64 {
        self.xi
    }

    /// The distortion coefficients `[k1, k2, p1, p2]`.
    pub fn radtan(&self) -> [f64; 4] {
        let d = self.distortion;
        [d.k1, d.k2, d.p1, d.p2]
    }

    /// Whether `p_cam` lies in the sphere projection's valid domain (see the
    /// type's documentation; distortion not considered).
    fn in_sphere_domain(&self, p_cam: &Vector3<f64>) -> bool {
        let norm = p_cam.norm();
        let w = if self.xi <= 1.0 {
            self.xi
        } else {
            1.0 / self.xi
        };
        norm > 0.0 && p_cam.z > -w * norm
    }

    /// The undistorted normalised coordinates of a valid point.
    fn normalised(&self, p_cam: &Vector3<f64>) -> Option<Vector2<f64>> {
        if !self.in_sphere_domain(p_cam) {
            return None;
        }
        let denom = p_cam.z + self.xi * p_cam.norm();
        let m = Vector2::new(p_cam.x / denom, p_cam.y / denom);
        (denom > 0.0 && self.distortion.is_valid(m)).then_some(m)
    }

    /// Whether a point of the camera frame lies in the valid domain (see the
    /// type's documentation); the origin does not.
    pub fn is_valid_point(&self, p_cam: &Vector3<f64>) -> bool {
        self.normalised(p_cam).is_some()
    }

    /// The full field of view, degrees: from the sphere condition
    /// (`acos(-xi)` for `xi <= 1`, `acos(-1 / xi)` beyond) and, with
    /// radial distortion, the angle whose `|m|` reaches the distortion's
    /// monotonic radius `r`: `atan(r) + asin(r xi / sqrt(1 + r^2))`
    /// (tangential terms ignored).
    pub fn max_fov_deg(&self) -> f64 {
        let xi = self.xi;
        let sphere = if xi <= 1.0 {
            (-xi).acos()
        } else {
            (-1.0 / xi).acos()
        };
        let r = self.distortion.max_r2().sqrt();
        let s = r * xi / (1.0 + r * r).sqrt();
        let half = if r.is_finite() && s <= 1.0 {
            sphere.min(r.atan() + s.asin())
        } else {
            sphere
        };
        2.0 * half.to_degrees()
    }

    /// Projects a point of the camera frame to a pixel; `None` outside the
    /// valid domain ([`Self::is_valid_point`]).
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        let m = self.distortion.distort(self.normalised(p_cam)?);
        Some(self.focal.pixel(m.x, m.y))
    }

    /// The unit ray (camera frame) of a pixel: the distortion is inverted by
    /// Gauss-Newton iteration, then `m` is lifted onto the unit sphere,
    /// `ray = (xi + sqrt(1 + (1 - xi^2) r^2)) / (r^2 + 1) (mx, my, 1) - (0, 0, xi)`.
    /// `None` if the iteration does not converge, or outside the image of the
    /// valid domain (for `xi > 1`, `r^2 >= 1 / (xi^2 - 1)`).
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        let (mx, my) = self.focal.plane(px);
        let m_distorted = Vector2::new(mx, my);
        let m = self.distortion.undistort(m_distorted)?;
        let r2 = m.norm_squared();
        let disc = 1.0 + (1.0 - self.xi * self.xi) * r2;
        if disc <= 0.0 {
            return None;
        }
        let scale = (self.xi + disc.sqrt()) / (r2 + 1.0);
        let ray = Vector3::new(scale * m.x, scale * m.y, scale - self.xi).try_normalize(0.0)?;
        (ray.iter().all(|v| v.is_finite()) && self.in_sphere_domain(&ray)).then_some(ray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::test_support::{check_round_trips, pixel_grid, rays_up_to};

    fn distorted() -> Unified {
        Unified::with_radtan(
            750.0,
            748.0,
            640.5,
            511.0,
            1.7,
            [-0.22, 0.03, 0.0004, -0.0002],
        )
        .unwrap()
    }

    #[test]
    fn golden_projection_by_hand() {
        // xi = 1 without distortion, p = (1, -2, 2): |p| = 3, z + xi |p| = 5,
        // m = (0.2, -0.4): col = 300 * 0.2 + 320 = 380, row = 310 * -0.4 + 240 = 116.
        let cam = Unified::new(300.0, 310.0, 320.0, 240.0, 1.0).unwrap();
        let px = cam.project(&Vector3::new(1.0, -2.0, 2.0)).unwrap();
        assert!((px.col - 380.0).abs() < 1e-12 && (px.row - 116.0).abs() < 1e-12);
        // The same point with radtan (k1, k2, p1, p2) = (-0.2, 0.05, 0.001, -0.002):
        // r^2 = 0.2, radial = 1 - 0.04 + 0.002 = 0.962,
        // x'' = 0.2 * 0.962 + 2 * 0.001 * (-0.08) - 0.002 * (0.2 + 0.08) = 0.19168,
        // y'' = -0.4 * 0.962 + 0.001 * (0.2 + 0.32) + 2 * (-0.002) * (-0.08) = -0.38396.
        let cam =
            Unified::with_radtan(300.0, 310.0, 320.0, 240.0, 1.0, [-0.2, 0.05, 0.001, -0.002])
                .unwrap();
        let px = cam.project(&Vector3::new(1.0, -2.0, 2.0)).unwrap();
        assert!((px.col - (300.0 * 0.19168 + 320.0)).abs() < 1e-9, "{px:?}");
        assert!((px.row - (310.0 * -0.38396 + 240.0)).abs() < 1e-9, "{px:?}");
    }

    #[test]
    fn round_trips() {
        let cams = [
            distorted(),
            Unified::new(300.0, 310.0, 500.0, 490.0, 0.0).unwrap(),
            Unified::new(300.0, 310.0, 500.0, 490.0, 0.8).unwrap(),
            Unified::new(300.0, 310.0, 500.0, 490.0, 1.0).unwrap(),
            Unified::new(300.0, 310.0, 500.0, 490.0, 2.5).unwrap(),
            Unified::with_radtan(300.0, 310.0, 500.0, 490.0, 0.9, [-0.1, 0.01, 0.001, 0.002])
                .unwrap(),
        ];
        for cam in cams {
            let half_fov = cam.max_fov_deg().to_radians() / 2.0;
            // Near the sphere limit |m| grows without bound, and with
            // distortion r^5 terms put the distorted point far beyond the
            // iteration's reach; end 5 % short of it there.
            let margin = if cam.radtan() == [0.0; 4] {
                1e-4
            } else {
                0.05 * half_fov
            };
            let rays = rays_up_to(half_fov - margin, 200);
            let n = check_round_trips(
                |p| cam.project(p),
                |px| cam.unproject(px),
                &pixel_grid(1280, 1024, 9),
                &rays,
            );
            assert!(n > 500, "{cam:?}: only {n} pixels unproject");
        }
    }

    #[test]
    fn points_outside_the_domain_do_not_project() {
        // xi = 0.8: the FOV is 2 acos(-0.8) = 286.26 degrees.
        let cam = Unified::new(300.0, 300.0, 0.0, 0.0, 0.8).unwrap();
        assert!((cam.max_fov_deg() - 2.0 * (-0.8f64).acos().to_degrees()).abs() < 1e-12);
        assert!(cam.project(&Vector3::new(0.7, 0.0, -0.7)).is_some());
        assert!(cam.project(&Vector3::new(0.0, 0.0, -1.0)).is_none());
        // xi = 2: valid only for z > -|p| / 2, i.e. up to 120 degrees.
        let cam = Unified::new(300.0, 300.0, 0.0, 0.0, 2.0).unwrap();
        assert!((cam.max_fov_deg() - 240.0).abs() < 1e-9);
        let a = 119f64.to_radians();
        assert!(cam.project(&Vector3::new(a.sin(), 0.0, a.cos())).is_some());
        let a = 121f64.to_radians();
        assert!(cam.project(&Vector3::new(a.sin(), 0.0, a.cos())).is_none());
        // r^2 beyond 1 / (xi^2 - 1) = 1/3 does not unproject.
        assert!(cam.unproject(Pixel::new(300.0 * 0.58, 0.0)).is_none());
        assert!(cam.unproject(Pixel::new(300.0 * 0.57, 0.0)).is_some());
    }

    #[test]
    fn invalid_parameters_are_named() {
        let cases = [
            (Unified::new(0.0, 1.0, 0.0, 0.0, 1.0), "fx"),
            (Unified::new(1.0, 1.0, 0.0, 0.0, -0.5), "xi"),
            (Unified::new(1.0, 1.0, 0.0, 0.0, f64::NAN), "xi"),
            (
                Unified::with_radtan(1.0, 1.0, 0.0, 0.0, 1.0, [0.0, f64::NAN, 0.0, 0.0]),
                "k2",
            ),
        ];
        for (result, name) in cases {
            match result {
                Err(CameraError::Param { model, param, .. }) => {
                    assert_eq!((model, param), ("omni", name));
                }
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
