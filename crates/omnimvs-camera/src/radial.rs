//! A camera projection written as a radial function and an affine map, for
//! projectors that tabulate it (the classical stereo's `SphereProjector`).

use crate::Pixel;

/// A central projection that factors into a radius, a function of the angle
/// from the optical axis only, and an affine map of the image plane. A point
/// `(x, y, z)` of the camera frame at angle `alpha` from the axis lands at
///
/// * `u = r(alpha) y / |(x, y)|` (along rows) and `v = r(alpha) x / |(x, y)|`
///   (along columns),
/// * `row = c u + d v + center.row`, `col = e u + v + center.col`,
///
/// exactly as [`crate::CameraModel::project`] computes it. Obtained from
/// [`crate::CameraModel::radial_projection`].
#[derive(Debug, Clone, PartialEq)]
pub struct RadialProjection {
    /// Half the field of view, radians: the largest `alpha` the camera sees.
    pub half_fov_rad: f64,
    /// Affine term `c` (rows per row-plane unit).
    pub c: f64,
    /// Affine term `d` (rows per column-plane unit).
    pub d: f64,
    /// Affine term `e` (columns per row-plane unit).
    pub e: f64,
    /// The image of the optical axis, pixels.
    pub center: Pixel,
    radius: Radius,
}

/// The radial function of each model.
#[derive(Debug, Clone, PartialEq)]
enum Radius {
    /// OCamCalib's `world2cam` polynomial in `theta = alpha - pi/2`.
    OcamWorld2Cam(Vec<f64>),
    /// A closed-form model's image-plane radius times `fx`.
    Central(Box<crate::CentralCamera>),
}

impl RadialProjection {
    /// The projection of an OCamCalib model.
    pub(crate) fn ocam(m: &crate::OcamModel) -> Self {
        Self {
            half_fov_rad: m.half_fov_rad(),
            c: m.c,
            d: m.d,
            e: m.e,
            center: Pixel::new(m.center_col, m.center_row),
            radius: Radius::OcamWorld2Cam(m.inv_poly.clone()),
        }
    }

    /// The projection of a closed-form model with a radial lens: `r = fx m(alpha)`, rows
    /// scaled by `fy / fx`, no shear.
    pub(crate) fn central(camera: &crate::CentralCamera) -> Self {
        let f = camera.lens.focal();
        Self {
            half_fov_rad: camera.half_fov_rad(),
            c: f.fy() / f.fx(),
            d: 0.0,
            e: 0.0,
            center: Pixel::new(f.cx(), f.cy()),
            radius: Radius::Central(Box::new(camera.clone())),
        }
    }

    /// `r(alpha)`: the distance from the centre on the image plane, in pixels
    /// (before the affine map), of a point at `alpha_rad` from the optical axis.
    pub fn radius_px(&self, alpha_rad: f64) -> f64 {
        match &self.radius {
            Radius::OcamWorld2Cam(inv_poly) => {
                crate::ocam::polyval(inv_poly, alpha_rad - std::f64::consts::FRAC_PI_2)
            }
            Radius::Central(camera) => camera.lens.focal().fx() * camera.plane_radius(alpha_rad),
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use crate::CameraModel;
    use crate::ocam::tests::sunny_cam1;

    /// The factorised form gives the model's own projection over a grid of angles.
    #[test]
    fn radius_and_affine_reproduce_the_projection() {
        let mut cam = sunny_cam1();
        (cam.c, cam.d, cam.e) = (1.01, 0.002, -0.003);
        let model = CameraModel::Ocam(cam);
        let radial = model.radial_projection().unwrap();
        for alpha_deg in (1..=109).step_by(6) {
            for azimuth_deg in (0..360).step_by(30) {
                let (alpha, azimuth) = (
                    f64::from(alpha_deg).to_radians(),
                    f64::from(azimuth_deg).to_radians(),
                );
                let p = Vector3::new(
                    alpha.sin() * azimuth.cos(),
                    alpha.sin() * azimuth.sin(),
                    alpha.cos(),
                );
                let want = model.project(&p).unwrap();
                let r = radial.radius_px(alpha);
                let (u, v) = (r * azimuth.sin(), r * azimuth.cos());
                let row = radial.c * u + radial.d * v + radial.center.row;
                let col = radial.e * u + v + radial.center.col;
                assert!(
                    (row - want.row).abs() < 1e-6 && (col - want.col).abs() < 1e-6,
                    "{alpha_deg} {azimuth_deg}"
                );
            }
        }
        assert!((radial.half_fov_rad - 110f64.to_radians()).abs() < 1e-12);
    }
}
