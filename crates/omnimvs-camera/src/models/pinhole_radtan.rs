use nalgebra::{Vector2, Vector3};

use super::radtan::RadTan;
use super::{Focal, check_finite};
use crate::{CameraError, Pixel};

const MODEL: &str = "pinhole-radtan";

/// Smallest `z / |p|` of a point in front of the camera.
const MIN_COS_ANGLE: f64 = 1e-9;

/// The pinhole model with OpenCV's and Kalibr's radial-tangential distortion
/// (`pinhole` + `radtan`):
///
/// * `x' = x / z`, `y' = y / z`, `r^2 = x'^2 + y'^2`,
///   `radial = 1 + k1 r^2 + k2 r^4`,
/// * `x'' = x' radial + 2 p1 x' y' + p2 (r^2 + 2 x'^2)`,
///   `y'' = y' radial + p1 (r^2 + 2 y'^2) + 2 p2 x' y'`,
/// * `col = fx x'' + cx`, `row = fy y'' + cy`.
///
/// Valid points lie in front of the camera (`z > 1e-9 |p|`) where the
/// distortion is one-to-one: `r^2` below the first root of
/// `1 + 3 k1 r^2 + 5 k2 r^4` (where `r radial` stops increasing) and a
/// positive Jacobian determinant of the distortion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinholeRadtan {
    focal: Focal,
    distortion: RadTan,
}

impl PinholeRadtan {
    /// A pinhole camera from its calibration: focal lengths `fx`, `fy` and
    /// principal point `cx`, `cy` in pixels (0-based), distortion
    /// coefficients `k1`, `k2`, `p1`, `p2` (all zero for no distortion).
    ///
    /// # Errors
    ///
    /// [`CameraError::Param`] naming the first parameter that is not finite
    /// or a focal length that is not positive.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        k1: f64,
        k2: f64,
        p1: f64,
        p2: f64,
    ) -> Result<Self, CameraError> {
        Ok(Self {
            focal: Focal::new(MODEL, fx, fy, cx, cy)?,
            distortion: RadTan {
                k1: check_finite(MODEL, "k1", k1)?,
                k2: check_finite(MODEL, "k2", k2)?,
                p1: check_finite(MODEL, "p1", p1)?,
                p2: check_finite(MODEL, "p2", p2)?,
            },
        })
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

    /// The distortion coefficients `[k1, k2, p1, p2]`.
    pub fn radtan(&self) -> [f64; 4] {
        let d = self.distortion;
        [d.k1, d.k2, d.p1, d.p2]
    }

    /// The undistorted normalised coordinates of a valid point.
    fn normalised(&self, p_cam: &Vector3<f64>) -> Option<Vector2<f64>> {
        let norm = p_cam.norm();
        if !(norm > 0.0 && p_cam.z > MIN_COS_ANGLE * norm) {
            return None;
        }
        let m = Vector2::new(p_cam.x / p_cam.z, p_cam.y / p_cam.z);
        self.distortion.is_valid(m).then_some(m)
    }

    /// Whether a point of the camera frame lies in the valid domain (see the
    /// type's documentation); points behind or beside the camera do not.
    pub fn is_valid_point(&self, p_cam: &Vector3<f64>) -> bool {
        self.normalised(p_cam).is_some()
    }

    /// The full field of view, degrees: `2 atan(r)` with `r` the radius where
    /// the radial distortion stops increasing (tangential terms ignored);
    /// 180 (exclusive) without such a radius.
    pub fn max_fov_deg(&self) -> f64 {
        2.0 * self.distortion.max_r2().sqrt().atan().to_degrees()
    }

    /// Projects a point of the camera frame to a pixel; `None` outside the
    /// valid domain ([`Self::is_valid_point`]).
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        let m = self.distortion.distort(self.normalised(p_cam)?);
        Some(self.focal.pixel(m.x, m.y))
    }

    /// The unit ray (camera frame) of a pixel, inverting the distortion by
    /// Gauss-Newton iteration; `None` if it does not converge or converges
    /// outside the valid domain.
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        let (mx, my) = self.focal.plane(px);
        let m_distorted = Vector2::new(mx, my);
        let m = self.distortion.undistort(m_distorted)?;
        Vector3::new(m.x, m.y, 1.0).try_normalize(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::test_support::{check_round_trips, pixel_grid, rays_up_to};

    /// Kalibr's EuRoC `cam0` calibration (pinhole + radtan), 752x480.
    fn euroc_cam0() -> PinholeRadtan {
        PinholeRadtan::new(
            458.654,
            457.296,
            367.215,
            248.375,
            -0.28340811,
            0.07395907,
            0.00019359,
            1.76187114e-05,
        )
        .unwrap()
    }

    #[test]
    fn golden_projection_by_hand() {
        // p = (1, -2, 4): x' = 0.25, y' = -0.5, x' y' = -0.125, r^2 = 0.3125,
        // radial = 1 - 0.28340811 * 0.3125 + 0.07395907 * 0.09765625
        //        = 0.9186575310546875,
        // x'' = 0.25 radial + 2 p1 (-0.125) + p2 (0.3125 + 0.125) = 0.229623693449909375,
        // y'' = -0.5 radial + p1 (0.3125 + 0.5) + 2 p2 (-0.125) = -0.45917587833019375,
        // col = 458.654 x'' + 367.215 = 472.53282549557473,
        // row = 457.296 y'' + 248.375 = 38.395707543115719.
        let px = euroc_cam0().project(&Vector3::new(1.0, -2.0, 4.0)).unwrap();
        assert!((px.col - 472.53282549557473).abs() < 1e-9, "{px:?}");
        assert!((px.row - 38.395_707_543_115_72).abs() < 1e-9, "{px:?}");
    }

    #[test]
    fn round_trips() {
        let cams = [
            euroc_cam0(),
            PinholeRadtan::new(400.0, 410.0, 320.0, 240.0, 0.0, 0.0, 0.0, 0.0).unwrap(),
            PinholeRadtan::new(400.0, 410.0, 320.0, 240.0, 0.1, 0.02, -0.001, 0.002).unwrap(),
            PinholeRadtan::new(300.0, 310.0, 376.0, 240.0, -0.3, 0.0, 0.001, -0.001).unwrap(),
        ];
        for cam in cams {
            // max_fov_deg ignores the tangential terms, which can narrow the
            // domain slightly.
            let half_fov = (cam.max_fov_deg().to_radians() / 2.0).min(80f64.to_radians());
            let rays = rays_up_to(0.98 * half_fov, 200);
            let n = check_round_trips(
                |p| cam.project(p),
                |px| cam.unproject(px),
                &pixel_grid(752, 480, 3),
                &rays,
            );
            assert!(n > 1000, "{cam:?}: only {n} pixels unproject");
        }
    }

    #[test]
    fn points_behind_the_camera_do_not_project() {
        let cam = euroc_cam0();
        assert!(cam.project(&Vector3::new(0.1, 0.2, -1.0)).is_none());
        assert!(cam.project(&Vector3::new(1.0, 0.0, 0.0)).is_none());
        assert!(cam.project(&Vector3::zeros()).is_none());
        // EuRoC's r (1 + k1 r^2 + k2 r^4) increases everywhere: 1 - 0.85 s + 0.37 s^2
        // has no real root.
        assert_eq!(cam.max_fov_deg(), 180.0);
        // Barrel distortion k1 = -0.2: r (1 - 0.2 r^2) stops increasing at
        // r^2 = 1 / 0.6, i.e. 2 atan(1.29) = 104.5 degrees.
        let barrel = PinholeRadtan::new(400.0, 400.0, 0.0, 0.0, -0.2, 0.0, 0.0, 0.0).unwrap();
        let half = (1.0f64 / 0.6).sqrt().atan();
        assert!((barrel.max_fov_deg() - 2.0 * half.to_degrees()).abs() < 1e-12);
        let a = half + 1e-3;
        assert!(
            barrel
                .project(&Vector3::new(a.sin(), 0.0, a.cos()))
                .is_none()
        );
        let a = half - 1e-3;
        assert!(
            barrel
                .project(&Vector3::new(a.sin(), 0.0, a.cos()))
                .is_some()
        );
        // The image of that radius bounds the pixels that unproject.
        let r_max_px = 400.0 * half.tan() * (1.0 - 0.2 * half.tan().powi(2));
        assert!(
            barrel
                .unproject(Pixel::new(r_max_px * 0.999, 0.0))
                .is_some()
        );
        assert!(
            barrel
                .unproject(Pixel::new(r_max_px * 1.001, 0.0))
                .is_none()
        );
        let plain = PinholeRadtan::new(400.0, 400.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0).unwrap();
        assert_eq!(plain.max_fov_deg(), 180.0);
    }

    #[test]
    fn invalid_parameters_are_named() {
        let cases = [
            (
                PinholeRadtan::new(0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
                "fx",
            ),
            (
                PinholeRadtan::new(1.0, f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
                "fy",
            ),
            (
                PinholeRadtan::new(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, f64::INFINITY, 0.0),
                "p1",
            ),
        ];
        for (result, name) in cases {
            match result {
                Err(CameraError::Param { model, param, .. }) => {
                    assert_eq!((model, param), ("pinhole-radtan", name));
                }
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
