use nalgebra::Vector3;

use super::{Focal, check_range};
use crate::{CameraError, Pixel};

const MODEL: &str = "ds";

/// The double sphere camera model of Usenko, Demmel and Cremers, "The Double
/// Sphere Camera Model", 3DV 2018 (Basalt's `ds`).
///
/// A point `p = (x, y, z)` is projected onto a unit sphere, shifted by `xi`
/// along the optical axis onto a second unit sphere, and projected by a
/// pinhole shifted by `alpha / (1 - alpha)`:
///
/// * `d1 = |p|`, `d2 = sqrt(x^2 + y^2 + (xi d1 + z)^2)`,
/// * `col = fx x / (alpha d2 + (1 - alpha)(xi d1 + z)) + cx`, likewise `row`
///   with `fy`, `y`, `cy`.
///
/// Valid points are those with `z > -w2 d1`, where
/// `w2 = (w1 + xi) / sqrt(2 w1 xi + xi^2 + 1)` and `w1 = alpha / (1 - alpha)`
/// if `alpha <= 0.5`, else `(1 - alpha) / alpha` (the paper's condition; it
/// is sufficient and slightly narrower than the full domain where the
/// projection is one-to-one, so the two directions agree on it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoubleSphere {
    focal: Focal,
    xi: f64,
    alpha: f64,
    /// `w2` of the validity condition, from `xi` and `alpha` (`Self::w2`).
    w2: f64,
}

impl DoubleSphere {
    /// A double sphere camera from its calibration: focal lengths `fx`, `fy`
    /// and principal point `cx`, `cy` in pixels (0-based), `xi` in `[-1, 1]`
    /// and `alpha` in `[0, 1]`.
    ///
    /// # Errors
    ///
    /// [`CameraError::Param`] naming the first parameter that is not finite,
    /// a focal length that is not positive, or `xi` or `alpha` outside its
    /// interval.
    pub fn new(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        xi: f64,
        alpha: f64,
    ) -> Result<Self, CameraError> {
        let focal = Focal::new(MODEL, fx, fy, cx, cy)?;
        let (xi, alpha) = (
            check_range(MODEL, "xi", xi, -1.0, 1.0)?,
            check_range(MODEL, "alpha", alpha, 0.0, 1.0)?,
        );
        Ok(Self {
            focal,
            xi,
            alpha,
            w2: Self::w2(xi, alpha),
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

    /// Shift between the two spheres, in units of their radius.
    pub fn xi(&self) -> f64 {
        self.xi
    }

    /// Weight of the second sphere's pinhole shift.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// `w2` of the validity condition `z > -w2 |p|`: minus the cosine of the
    /// largest angle from the optical axis that the model projects.
    fn w2(xi: f64, alpha: f64) -> f64 {
        let w1 = if alpha <= 0.5 {
            alpha / (1.0 - alpha)
        } else {
            (1.0 - alpha) / alpha
        };
        (w1 + xi) / (2.0 * w1 * xi + xi * xi + 1.0).sqrt()
    }

    /// Whether a point of the camera frame lies in the valid domain
    /// `z > -w2 |p|` (see the type's documentation); the origin does not.
    pub fn is_valid_point(&self, p_cam: &Vector3<f64>) -> bool {
        let d1 = p_cam.norm();
        d1 > 0.0 && p_cam.z > -self.w2 * d1
    }

    /// The full field of view, degrees: twice `acos(-w2)`.
    pub fn max_fov_deg(&self) -> f64 {
        2.0 * (-self.w2).clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// Projects a point of the camera frame to a pixel; `None` outside the
    /// valid domain ([`Self::is_valid_point`]).
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        // is_valid_point, sharing |p| with the projection.
        let d1 = p_cam.norm();
        if !(d1 > 0.0 && p_cam.z > -self.w2 * d1) {
            return None;
        }
        let (x, y, z) = (p_cam.x, p_cam.y, p_cam.z);
        let k = self.xi * d1 + z;
        let d2 = (x * x + y * y + k * k).sqrt();
        let denom = self.alpha * d2 + (1.0 - self.alpha) * k;
        if denom <= 0.0 {
            return None;
        }
        Some(self.focal.pixel(x / denom, y / denom))
    }

    /// The unit ray (camera frame) of a pixel. `None` where
    /// `r^2 = mx^2 + my^2` exceeds `1 / (2 alpha - 1)` for `alpha > 0.5`
    /// (`mx = (col - cx) / fx`, `my = (row - cy) / fy`), or where the ray
    /// falls outside the valid domain of [`Self::project`].
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        let (mx, my) = self.focal.plane(px);
        let r2 = mx * mx + my * my;
        let alpha = self.alpha;
        if alpha > 0.5 && r2 > 1.0 / (2.0 * alpha - 1.0) {
            return None;
        }
        let mz = (1.0 - alpha * alpha * r2)
            / (alpha * (1.0 - (2.0 * alpha - 1.0) * r2).sqrt() + 1.0 - alpha);
        let scale =
            (mz * self.xi + (mz * mz + (1.0 - self.xi * self.xi) * r2).sqrt()) / (mz * mz + r2);
        let ray = Vector3::new(scale * mx, scale * my, scale * mz - self.xi);
        let ray = ray.try_normalize(0.0)?;
        (ray.iter().all(|v| v.is_finite()) && self.is_valid_point(&ray)).then_some(ray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::test_support::{check_round_trips, pixel_grid, rays_up_to};

    /// The left camera of Basalt's TUM VI 512x512 calibration
    /// (`data/tumvi_512_ds_calib.json` in the Basalt repository).
    fn tumvi_left() -> DoubleSphere {
        DoubleSphere::new(
            158.28600034966977,
            158.2743455478755,
            254.96116578191653,
            256.8894394501779,
            -0.17213086034353243,
            0.5931177593944744,
        )
        .unwrap()
    }

    #[test]
    fn golden_projection_by_hand() {
        // p = (1, -2, 3): d1 = sqrt(14) = 3.7416573867739413,
        // k = xi d1 + z = 3 - 0.17213086034353243 * 3.7416573867739413
        //   = 2.3559452949038682,
        // d2 = sqrt(1 + 4 + k^2) = 3.2481499707648467,
        // denom = alpha d2 + (1 - alpha) k = 2.8851277331718051,
        // col = fx / denom + cx = 309.82390150407323,
        // row = -2 fy / denom + cy = 147.17204723345659.
        let px = tumvi_left().project(&Vector3::new(1.0, -2.0, 3.0)).unwrap();
        assert!((px.col - 309.823_901_504_073_2).abs() < 1e-9, "{px:?}");
        assert!((px.row - 147.172_047_233_456_6).abs() < 1e-9, "{px:?}");
    }

    #[test]
    fn optical_axis_is_the_principal_point() {
        let cam = tumvi_left();
        let px = cam.project(&Vector3::new(0.0, 0.0, 2.0)).unwrap();
        assert!(
            (px.col - cam.focal().cx()).abs() < 1e-12 && (px.row - cam.focal().cy()).abs() < 1e-12
        );
        let ray = cam
            .unproject(Pixel::new(cam.focal().cx(), cam.focal().cy()))
            .unwrap();
        assert!((ray - Vector3::z()).norm() < 1e-12);
    }

    #[test]
    fn round_trips() {
        // Basalt's unit-test camera and parameters spanning both branches of alpha.
        let cams = [
            tumvi_left(),
            DoubleSphere::new(402.5, 400.0, 505.0, 509.0, -0.075347, 0.743925).unwrap(),
            DoubleSphere::new(300.0, 310.0, 500.0, 490.0, 0.5, 0.3).unwrap(),
            DoubleSphere::new(300.0, 310.0, 500.0, 490.0, 0.9, 0.8).unwrap(),
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
        let cam = tumvi_left();
        // w1 = (1 - alpha) / alpha = 0.6860, w2 = 0.5769:
        // the FOV is 2 acos(-w2) = 250.46 degrees.
        assert!((cam.max_fov_deg() - 250.46437819929218).abs() < 1e-9);
        let half = cam.max_fov_deg().to_radians() / 2.0;
        let inside = Vector3::new((half - 1e-3).sin(), 0.0, (half - 1e-3).cos());
        let outside = Vector3::new((half + 1e-3).sin(), 0.0, (half + 1e-3).cos());
        assert!(cam.project(&inside).is_some());
        assert!(cam.project(&outside).is_none());
        assert!(cam.project(&Vector3::new(0.0, 0.0, -1.0)).is_none());
        assert!(cam.project(&Vector3::zeros()).is_none());
        // alpha > 0.5: pixels beyond r^2 = 1 / (2 alpha - 1) do not unproject.
        let r_max = (1.0 / (2.0 * cam.alpha() - 1.0)).sqrt();
        let far = Pixel::new(
            cam.focal().cx() + cam.focal().fx() * r_max * 1.01,
            cam.focal().cy(),
        );
        assert!(cam.unproject(far).is_none());
    }

    #[test]
    fn invalid_parameters_are_named() {
        let cases = [
            (DoubleSphere::new(0.0, 1.0, 0.0, 0.0, 0.0, 0.5), "fx"),
            (DoubleSphere::new(1.0, -1.0, 0.0, 0.0, 0.0, 0.5), "fy"),
            (DoubleSphere::new(1.0, 1.0, f64::NAN, 0.0, 0.0, 0.5), "cx"),
            (
                DoubleSphere::new(1.0, 1.0, 0.0, f64::INFINITY, 0.0, 0.5),
                "cy",
            ),
            (DoubleSphere::new(1.0, 1.0, 0.0, 0.0, 1.5, 0.5), "xi"),
            (DoubleSphere::new(1.0, 1.0, 0.0, 0.0, 0.0, 1.1), "alpha"),
            (DoubleSphere::new(1.0, 1.0, 0.0, 0.0, 0.0, -0.1), "alpha"),
        ];
        for (result, name) in cases {
            match result {
                Err(CameraError::Param { model, param, .. }) => {
                    assert_eq!((model, param), ("ds", name));
                }
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
