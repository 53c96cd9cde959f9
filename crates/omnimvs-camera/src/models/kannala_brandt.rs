use nalgebra::Vector3;

use super::{Focal, check_finite};
use crate::batch::BATCH_LANES;
use crate::{CameraError, Pixel};

const MODEL: &str = "kb4";

/// The largest default half field of view, radians (125 degrees).
const MAX_HALF_FOV_RAD: f64 = 125.0 * std::f64::consts::PI / 180.0;

/// Most Newton steps [`KannalaBrandt4::unproject`] takes.
const UNPROJECT_MAX_ITERATIONS: usize = 50;

/// Step of the scan for the first stationary point of `d(theta)`, radians.
const SCAN_STEP_RAD: f64 = 1e-3;

/// The generic fisheye model of Kannala and Brandt, "A Generic Camera Model
/// and Calibration Method for Conventional, Wide-Angle, and Fish-Eye Lenses",
/// IEEE TPAMI 2006, with four coefficients: Kalibr's `pinhole` +
/// `equidistant`, OpenCV's `fisheye` module and Basalt's `kb4`.
///
/// With `theta = atan2(sqrt(x^2 + y^2), z)` the angle from the optical axis,
///
/// * `d(theta) = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)`,
/// * `col = fx d(theta) x / r + cx`, `row = fy d(theta) y / r + cy` with
///   `r = sqrt(x^2 + y^2)` (the principal point for `r = 0`).
///
/// Valid points are those with `theta <= max_fov_deg / 2`, a bound within
/// which `d` strictly increases; it may exceed 90 degrees (lenses up to
/// 250 degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KannalaBrandt4 {
    focal: Focal,
    k1: f64,
    k2: f64,
    k3: f64,
    k4: f64,
    max_theta_rad: f64,
}

impl KannalaBrandt4 {
    /// A Kannala-Brandt camera from its calibration: focal lengths `fx`, `fy`
    /// and principal point `cx`, `cy` in pixels (0-based), coefficients
    /// `k1..k4`. The field of view defaults to twice the smallest of 125
    /// degrees and the first angle where `d(theta)` stops increasing.
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
        k3: f64,
        k4: f64,
    ) -> Result<Self, CameraError> {
        let mut model = Self {
            focal: Focal::new(MODEL, fx, fy, cx, cy)?,
            k1: check_finite(MODEL, "k1", k1)?,
            k2: check_finite(MODEL, "k2", k2)?,
            k3: check_finite(MODEL, "k3", k3)?,
            k4: check_finite(MODEL, "k4", k4)?,
            max_theta_rad: 0.0,
        };
        // d'(0) = 1, so the bound is positive.
        model.max_theta_rad = model.monotonic_theta_rad(MAX_HALF_FOV_RAD);
        Ok(model)
    }

    /// The same camera with its field of view set to `max_fov_deg` degrees.
    ///
    /// # Errors
    ///
    /// [`CameraError::Param`] naming `max_fov_deg` when it is not in
    /// `(0, 360]` or when `d(theta)` stops increasing before half of it.
    pub fn with_max_fov_deg(self, max_fov_deg: f64) -> Result<Self, CameraError> {
        let half = max_fov_deg.to_radians() / 2.0;
        if !(max_fov_deg > 0.0 && max_fov_deg <= 360.0) {
            return Err(CameraError::param(
                MODEL,
                "max_fov_deg",
                format!("must lie in (0, 360], got {max_fov_deg}"),
            ));
        }
        let monotonic = self.monotonic_theta_rad(half);
        if monotonic < half {
            return Err(CameraError::param(
                MODEL,
                "max_fov_deg",
                format!(
                    "d(theta) stops increasing at {:.3} degrees from the axis, before half of {max_fov_deg}",
                    monotonic.to_degrees()
                ),
            ));
        }
        Ok(Self {
            max_theta_rad: half,
            ..self
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

    /// The distortion coefficients `[k1, k2, k3, k4]`.
    pub fn k(&self) -> [f64; 4] {
        [self.k1, self.k2, self.k3, self.k4]
    }

    /// The full field of view, degrees: twice the largest valid `theta`.
    pub fn max_fov_deg(&self) -> f64 {
        2.0 * self.max_theta_rad.to_degrees()
    }

    /// `d(theta)`, the normalised image radius at `theta` radians.
    pub fn d(&self, theta_rad: f64) -> f64 {
        let t2 = theta_rad * theta_rad;
        theta_rad * (1.0 + t2 * (self.k1 + t2 * (self.k2 + t2 * (self.k3 + t2 * self.k4))))
    }

    /// `d'(theta) = 1 + 3 k1 theta^2 + 5 k2 theta^4 + 7 k3 theta^6 + 9 k4 theta^8`.
    fn d_prime(&self, theta_rad: f64) -> f64 {
        let t2 = theta_rad * theta_rad;
        1.0 + t2
            * (3.0 * self.k1 + t2 * (5.0 * self.k2 + t2 * (7.0 * self.k3 + t2 * 9.0 * self.k4)))
    }

    /// The first `theta` in `(0, limit]` where `d'` vanishes (by a scan and
    /// bisection), or `limit` if `d'` stays positive.
    fn monotonic_theta_rad(&self, limit_rad: f64) -> f64 {
        let mut lo = 0.0;
        while lo < limit_rad {
            let hi = (lo + SCAN_STEP_RAD).min(limit_rad);
            if self.d_prime(hi) <= 0.0 {
                let (mut a, mut b) = (lo, hi);
                for _ in 0..60 {
                    let mid = 0.5 * (a + b);
                    if self.d_prime(mid) > 0.0 {
                        a = mid
                    } else {
                        b = mid
                    }
                }
                return a;
            }
            lo = hi;
        }
        limit_rad
    }

    /// Whether a point of the camera frame lies within the field of view;
    /// the origin does not.
    pub fn is_valid_point(&self, p_cam: &Vector3<f64>) -> bool {
        let r = (p_cam.x * p_cam.x + p_cam.y * p_cam.y).sqrt();
        (r > 0.0 || p_cam.z > 0.0) && r.atan2(p_cam.z) <= self.max_theta_rad
    }

    /// Projects a point of the camera frame to a pixel; `None` outside the
    /// field of view.
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        let r = (p_cam.x * p_cam.x + p_cam.y * p_cam.y).sqrt();
        self.pixel_of(p_cam, r, r.atan2(p_cam.z))
    }

    /// [`Self::project`] of every point of `points` into `pixels` (same length), with the
    /// same result to the bit: the angles first, then the polynomials and divisions of
    /// eight points, which overlap instead of waiting on one another.
    pub fn project_many(&self, points: &[Vector3<f64>], pixels: &mut [Option<Pixel>]) {
        debug_assert_eq!(points.len(), pixels.len());
        let mut chunks = points.chunks_exact(BATCH_LANES);
        let mut outs = pixels.chunks_exact_mut(BATCH_LANES);
        for (p, out) in (&mut chunks).zip(&mut outs) {
            let (mut r, mut theta) = ([0.0; BATCH_LANES], [0.0; BATCH_LANES]);
            for l in 0..BATCH_LANES {
                r[l] = (p[l].x * p[l].x + p[l].y * p[l].y).sqrt();
                theta[l] = r[l].atan2(p[l].z);
            }
            for l in 0..BATCH_LANES {
                out[l] = self.pixel_of(&p[l], r[l], theta[l]);
            }
        }
        for (p, out) in chunks.remainder().iter().zip(outs.into_remainder()) {
            *out = self.project(p);
        }
    }

    /// The end of [`Self::project`] once `r = sqrt(x^2 + y^2)` and `theta = atan2(r, z)` are
    /// known: [`Self::is_valid_point`] and the pixel.
    #[inline(always)]
    fn pixel_of(&self, p_cam: &Vector3<f64>, r: f64, theta: f64) -> Option<Pixel> {
        if !((r > 0.0 || p_cam.z > 0.0) && theta <= self.max_theta_rad) {
            return None;
        }
        if r == 0.0 {
            return Some(self.focal.pixel(0.0, 0.0));
        }
        let scale = self.d(theta) / r;
        Some(self.focal.pixel(scale * p_cam.x, scale * p_cam.y))
    }

    /// The unit ray (camera frame) of a pixel: `theta` solves
    /// `d(theta) = sqrt(mx^2 + my^2)` (`mx = (col - cx) / fx`,
    /// `my = (row - cy) / fy`) by Newton iteration kept inside
    /// `[0, max_theta]` by bisection, to 1e-12 relative. `None` beyond the
    /// field of view or if it does not converge.
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        let (mx, my) = self.focal.plane(px);
        let r = mx.hypot(my);
        if r == 0.0 {
            return Some(Vector3::z());
        }
        // The image radius of a point on the boundary, recomputed from its
        // pixel, may exceed d(max_theta) by rounding.
        if !r.is_finite() || r > self.d(self.max_theta_rad) * (1.0 + 1e-12) {
            return None;
        }
        let theta = self.solve_theta(r)?;
        let s = theta.sin() / r;
        Some(Vector3::new(s * mx, s * my, theta.cos()))
    }

    /// `theta` in `[0, max_theta]` with `d(theta) = r`, for
    /// `0 < r <= d(max_theta)`.
    fn solve_theta(&self, r: f64) -> Option<f64> {
        let (mut lo, mut hi) = (0.0, self.max_theta_rad);
        let mut theta = r.min(hi);
        for _ in 0..UNPROJECT_MAX_ITERATIONS {
            let f = self.d(theta) - r;
            if f.abs() <= 1e-15 * r.max(1.0) {
                return Some(theta);
            }
            if f > 0.0 {
                hi = theta
            } else {
                lo = theta
            }
            let newton = theta - f / self.d_prime(theta);
            let next = if newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if (next - theta).abs() <= 1e-12 * theta.max(1e-300) && f.abs() <= 1e-12 * r {
                return Some(next);
            }
            theta = next;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::test_support::{check_round_trips, pixel_grid, rays_up_to};

    /// Basalt's T265 Kannala-Brandt calibration, left camera
    /// (`data/t265_kb4_calib.json` in the Basalt repository).
    fn t265() -> KannalaBrandt4 {
        KannalaBrandt4::new(
            286.60144163375528,
            286.4617087423328,
            422.2765876951761,
            395.2246466040553,
            -0.006762412326815424,
            0.045170283325720008,
            -0.043515167278210638,
            0.008374959821591333,
        )
        .unwrap()
    }

    #[test]
    fn golden_projection_by_hand() {
        // OpenCV's fisheye formula with fx = 300, fy = 310, cx = 320,
        // cy = 240, k = (0.1, -0.01, 0.001, -0.0001), p = (3, 4, 5):
        // r = 5, theta = atan(5 / 5) = pi/4 = 0.7853981633974483,
        // theta^2 = 0.6168502750680849, theta_d = theta (1 + 0.1 t2 - 0.01 t2^2
        // + 0.001 t2^3 - 0.0001 t2^4) = 0.8310299700262919,
        // col = 300 * theta_d * 3 / 5 + 320 = 469.58539460473254,
        // row = 310 * theta_d * 4 / 5 + 240 = 446.09543256652039.
        let cam =
            KannalaBrandt4::new(300.0, 310.0, 320.0, 240.0, 0.1, -0.01, 0.001, -0.0001).unwrap();
        let px = cam.project(&Vector3::new(3.0, 4.0, 5.0)).unwrap();
        assert!((px.col - 469.585_394_604_732_5).abs() < 1e-9, "{px:?}");
        assert!((px.row - 446.095_432_566_520_4).abs() < 1e-9, "{px:?}");
        let ray = cam.unproject(px).unwrap();
        assert!((ray - Vector3::new(3.0, 4.0, 5.0).normalize()).norm() < 1e-12);
    }

    #[test]
    fn round_trips() {
        let equidistant = KannalaBrandt4::new(300.0, 300.0, 500.0, 500.0, 0.0, 0.0, 0.0, 0.0)
            .unwrap()
            .with_max_fov_deg(250.0)
            .unwrap();
        for cam in [t265(), equidistant] {
            let half_fov = cam.max_fov_deg().to_radians() / 2.0;
            let rays = rays_up_to(half_fov, 250);
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
    fn field_of_view_bounds_the_domain() {
        let cam = KannalaBrandt4::new(300.0, 300.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0).unwrap();
        // Equidistant: d increases everywhere, so the default cap applies.
        assert!((cam.max_fov_deg() - 250.0).abs() < 1e-9);
        let a = 124f64.to_radians();
        assert!(cam.project(&Vector3::new(a.sin(), 0.0, a.cos())).is_some());
        let a = 126f64.to_radians();
        assert!(cam.project(&Vector3::new(a.sin(), 0.0, a.cos())).is_none());
        assert!(cam.project(&Vector3::new(0.0, 0.0, -1.0)).is_none());
        assert!(
            cam.unproject(Pixel::new(300.0 * 126f64.to_radians(), 0.0))
                .is_none()
        );
        // k1 = -0.1: d'(theta) = 1 - 0.3 theta^2 vanishes at sqrt(1 / 0.3).
        let cam = KannalaBrandt4::new(300.0, 300.0, 0.0, 0.0, -0.1, 0.0, 0.0, 0.0).unwrap();
        let want = 2.0 * (1.0f64 / 0.3).sqrt().to_degrees();
        assert!(
            (cam.max_fov_deg() - want).abs() < 1e-9,
            "{}",
            cam.max_fov_deg()
        );
        assert!(cam.with_max_fov_deg(220.0).is_err());
        assert!(cam.with_max_fov_deg(180.0).is_ok());
    }

    #[test]
    fn invalid_parameters_are_named() {
        let cam = |fx, k1, k4| KannalaBrandt4::new(fx, 1.0, 0.0, 0.0, k1, 0.0, 0.0, k4);
        let cases = [
            (cam(0.0, 0.0, 0.0), "fx"),
            (cam(1.0, f64::NAN, 0.0), "k1"),
            (cam(1.0, 0.0, f64::INFINITY), "k4"),
            (
                cam(1.0, 0.0, 0.0).and_then(|c| c.with_max_fov_deg(400.0)),
                "max_fov_deg",
            ),
            (
                cam(1.0, 0.0, 0.0).and_then(|c| c.with_max_fov_deg(-1.0)),
                "max_fov_deg",
            ),
        ];
        for (result, name) in cases {
            match result {
                Err(CameraError::Param { model, param, .. }) => {
                    assert_eq!((model, param), ("kb4", name));
                }
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
