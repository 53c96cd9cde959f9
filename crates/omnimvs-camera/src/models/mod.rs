//! Central fisheye and pinhole camera models with closed-form or iterative
//! exact projection and unprojection.
//!
//! * [`DoubleSphere`]: Usenko, Demmel and Cremers, "The Double Sphere Camera
//!   Model", 3DV 2018.
//! * [`ExtendedUnified`]: Khomutenko, Garcia and Martinet, "An Enhanced Unified
//!   Camera Model", IEEE RA-L 2016.
//! * [`Unified`]: Mei and Rives, "Single View Point Omnidirectional Camera
//!   Calibration from Planar Grids", ICRA 2007, with optional
//!   radial-tangential distortion.
//! * [`KannalaBrandt4`]: Kannala and Brandt, "A Generic Camera Model and
//!   Calibration Method for Conventional, Wide-Angle, and Fish-Eye Lenses",
//!   IEEE TPAMI 2006 (the four-coefficient form of OpenCV's fisheye module).
//! * [`PinholeRadtan`]: the pinhole model with OpenCV's radial-tangential
//!   distortion.
//!
//! All share the crate's conventions: points in the camera frame (x right,
//! y down, z forward along the optical axis), [`crate::Pixel`] `(col, row)`
//! 0-based with pixel centres at integers, `fx`/`cx` along columns and
//! `fy`/`cy` along rows. `project` returns `None` for a point outside the
//! model's valid domain; `unproject` returns a unit ray, or `None` for a pixel
//! outside the image of that domain. Each model's `max_fov_deg` is twice the
//! largest angle from the optical axis that it projects.

mod double_sphere;
mod extended_unified;
mod kannala_brandt;
mod pinhole_radtan;
mod radtan;
mod unified;

pub use double_sphere::DoubleSphere;
pub use extended_unified::ExtendedUnified;
pub use kannala_brandt::KannalaBrandt4;
pub use pinhole_radtan::PinholeRadtan;
pub use unified::Unified;

use crate::{CameraError, Pixel};

/// The pinhole step every model ends with: focal lengths and principal point, pixels
/// (`fx`, `cx` along columns, `fy`, `cy` along rows, 0-based).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Focal {
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
}

impl Focal {
    /// Checks the four values of `model`.
    pub(crate) fn new(
        model: &'static str,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
    ) -> Result<Self, CameraError> {
        Ok(Self {
            fx: check_focal(model, "fx", fx)?,
            fy: check_focal(model, "fy", fy)?,
            cx: check_finite(model, "cx", cx)?,
            cy: check_finite(model, "cy", cy)?,
        })
    }

    /// Focal length along columns, pixels.
    pub fn fx(&self) -> f64 {
        self.fx
    }

    /// Focal length along rows, pixels.
    pub fn fy(&self) -> f64 {
        self.fy
    }

    /// Principal point column, pixels, 0-based.
    pub fn cx(&self) -> f64 {
        self.cx
    }

    /// Principal point row, pixels, 0-based.
    pub fn cy(&self) -> f64 {
        self.cy
    }

    /// The pixel of a point `(mx, my)` of the model's image plane.
    pub(crate) fn pixel(&self, mx: f64, my: f64) -> Pixel {
        Pixel::new(self.fx * mx + self.cx, self.fy * my + self.cy)
    }

    /// The same pinhole step for images scaled by `sc` along columns and `sr` along rows
    /// (pixel centres map as `(p + 0.5) s - 0.5`).
    pub(crate) fn scaled(&self, sc: f64, sr: f64) -> Self {
        Self {
            fx: self.fx * sc,
            fy: self.fy * sr,
            cx: (self.cx + 0.5) * sc - 0.5,
            cy: (self.cy + 0.5) * sr - 0.5,
        }
    }

    /// The image-plane point of a pixel, the inverse of [`Self::pixel`].
    pub(crate) fn plane(&self, px: Pixel) -> (f64, f64) {
        ((px.col - self.cx) / self.fx, (px.row - self.cy) / self.fy)
    }
}

/// Checks that a focal length is finite and positive.
pub(crate) fn check_focal(
    model: &'static str,
    param: &'static str,
    value_px: f64,
) -> Result<f64, CameraError> {
    if value_px.is_finite() && value_px > 0.0 {
        Ok(value_px)
    } else {
        Err(CameraError::param(
            model,
            param,
            format!("must be a finite positive focal length in pixels, got {value_px}"),
        ))
    }
}

/// Checks that a parameter is finite.
pub(crate) fn check_finite(
    model: &'static str,
    param: &'static str,
    value: f64,
) -> Result<f64, CameraError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(CameraError::param(
            model,
            param,
            format!("must be finite, got {value}"),
        ))
    }
}

/// Checks that a parameter lies in the closed interval `[lo, hi]`.
pub(crate) fn check_range(
    model: &'static str,
    param: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
) -> Result<f64, CameraError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(CameraError::param(
            model,
            param,
            format!("must lie in [{lo}, {hi}], got {value}"),
        ))
    }
}

/// Grids of rays and pixels shared by the models' round-trip tests.
#[cfg(test)]
pub(crate) mod test_support {
    use nalgebra::Vector3;

    use crate::Pixel;

    /// Unit rays at angles `0..=max_angle_rad` from the optical axis (in
    /// `steps` steps) and 24 azimuths.
    pub(crate) fn rays_up_to(max_angle_rad: f64, steps: u32) -> Vec<Vector3<f64>> {
        let mut rays = Vec::new();
        for i in 0..=steps {
            let angle = max_angle_rad * f64::from(i) / f64::from(steps);
            for j in 0..24 {
                let azimuth = std::f64::consts::TAU * f64::from(j) / 24.0 + 0.1;
                rays.push(Vector3::new(
                    angle.sin() * azimuth.cos(),
                    angle.sin() * azimuth.sin(),
                    angle.cos(),
                ));
            }
        }
        rays
    }

    /// Pixels on a grid with `step` pixels spacing over `width x height`.
    pub(crate) fn pixel_grid(width: u32, height: u32, step: usize) -> Vec<Pixel> {
        let mut pixels = Vec::new();
        for row in (0..height).step_by(step) {
            for col in (0..width).step_by(step) {
                pixels.push(Pixel::new(f64::from(col) + 0.25, f64::from(row) + 0.5));
            }
        }
        pixels
    }

    /// The angle between two rays, radians (robust for small angles).
    pub(crate) fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
        a.cross(b).norm().atan2(a.dot(b))
    }

    /// Checks `project(unproject(px)) == px` to 1e-9 pixel for every pixel
    /// that unprojects, and `unproject(project(ray)) == ray` to 1e-9 rad for
    /// every ray; returns how many pixels unprojected.
    pub(crate) fn check_round_trips(
        project: impl Fn(&Vector3<f64>) -> Option<Pixel>,
        unproject: impl Fn(Pixel) -> Option<Vector3<f64>>,
        pixels: &[Pixel],
        rays: &[Vector3<f64>],
    ) -> usize {
        let mut unprojected = 0;
        for &px in pixels {
            let Some(ray) = unproject(px) else { continue };
            unprojected += 1;
            assert!((ray.norm() - 1.0).abs() < 1e-12, "{px:?} {ray:?}");
            let back = project(&ray).unwrap_or_else(|| panic!("{px:?} -> {ray:?}"));
            assert!(
                (back.col - px.col).abs() < 1e-9 && (back.row - px.row).abs() < 1e-9,
                "{px:?} -> {back:?}"
            );
        }
        for ray in rays {
            let px = project(ray).unwrap_or_else(|| panic!("{ray:?}"));
            let back = unproject(px).unwrap_or_else(|| panic!("{ray:?} -> {px:?}"));
            assert!(angle_between(ray, &back) < 1e-9, "{ray:?} -> {back:?}");
        }
        unprojected
    }
}
