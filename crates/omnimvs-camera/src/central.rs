//! A camera of one of the closed-form models ([`crate::models`]) with the size of its images
//! and an optional narrower field of view: the [`crate::CameraModel::Central`] variant.

use nalgebra::Vector3;

use crate::batch::FovCone;
use crate::models::{DoubleSphere, ExtendedUnified, Focal, KannalaBrandt4, PinholeRadtan, Unified};
use crate::{CameraError, Pixel};

/// One of the closed-form lens models, by the name calibration tools give it.
#[derive(Debug, Clone, PartialEq)]
pub enum Lens {
    /// Double sphere (`ds`).
    DoubleSphere(DoubleSphere),
    /// Extended unified (`eucm`).
    ExtendedUnified(ExtendedUnified),
    /// Unified, Mei's omnidirectional model (`ucm`), with optional radial-tangential
    /// distortion.
    Unified(Unified),
    /// Kannala-Brandt with four coefficients (`kb4`).
    KannalaBrandt4(KannalaBrandt4),
    /// Pinhole with radial-tangential distortion (`pinhole-radtan`).
    PinholeRadtan(PinholeRadtan),
}

impl Lens {
    /// The model's name in `config.yaml`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::DoubleSphere(_) => "ds",
            Self::ExtendedUnified(_) => "eucm",
            Self::Unified(_) => "ucm",
            Self::KannalaBrandt4(_) => "kb4",
            Self::PinholeRadtan(_) => "pinhole-radtan",
        }
    }

    /// Projects a point of the camera frame; `None` outside the model's domain.
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        match self {
            Self::DoubleSphere(m) => m.project(p_cam),
            Self::ExtendedUnified(m) => m.project(p_cam),
            Self::Unified(m) => m.project(p_cam),
            Self::KannalaBrandt4(m) => m.project(p_cam),
            Self::PinholeRadtan(m) => m.project(p_cam),
        }
    }

    /// [`Self::project`] of every point of `points` into `pixels` (same length), with the
    /// same result to the bit; faster for the Kannala-Brandt model, whose polynomial and
    /// division run over several points at a time.
    pub fn project_many(&self, points: &[Vector3<f64>], pixels: &mut [Option<Pixel>]) {
        debug_assert_eq!(points.len(), pixels.len());
        match self {
            Self::KannalaBrandt4(m) => m.project_many(points, pixels),
            _ => {
                for (p_cam, out) in points.iter().zip(pixels.iter_mut()) {
                    *out = self.project(p_cam);
                }
            }
        }
    }

    /// The unit ray of a pixel; `None` outside the image of the model's domain.
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        match self {
            Self::DoubleSphere(m) => m.unproject(px),
            Self::ExtendedUnified(m) => m.unproject(px),
            Self::Unified(m) => m.unproject(px),
            Self::KannalaBrandt4(m) => m.unproject(px),
            Self::PinholeRadtan(m) => m.unproject(px),
        }
    }

    /// The widest field of view the model projects, degrees.
    pub fn max_fov_deg(&self) -> f64 {
        match self {
            Self::DoubleSphere(m) => m.max_fov_deg(),
            Self::ExtendedUnified(m) => m.max_fov_deg(),
            Self::Unified(m) => m.max_fov_deg(),
            Self::KannalaBrandt4(m) => m.max_fov_deg(),
            Self::PinholeRadtan(m) => m.max_fov_deg(),
        }
    }

    /// Focal lengths and principal point.
    pub fn focal(&self) -> Focal {
        match self {
            Self::DoubleSphere(m) => m.focal(),
            Self::ExtendedUnified(m) => m.focal(),
            Self::Unified(m) => m.focal(),
            Self::KannalaBrandt4(m) => m.focal(),
            Self::PinholeRadtan(m) => m.focal(),
        }
    }

    /// The same lens with other focal lengths and principal point.
    pub(crate) fn with_focal(&self, focal: Focal) -> Self {
        match self {
            Self::DoubleSphere(m) => Self::DoubleSphere(m.with_focal(focal)),
            Self::ExtendedUnified(m) => Self::ExtendedUnified(m.with_focal(focal)),
            Self::Unified(m) => Self::Unified(m.with_focal(focal)),
            Self::KannalaBrandt4(m) => Self::KannalaBrandt4(m.with_focal(focal)),
            Self::PinholeRadtan(m) => Self::PinholeRadtan(m.with_focal(focal)),
        }
    }

    /// Whether the projection depends on the angle from the optical axis only (before the
    /// focal lengths): false with tangential distortion.
    pub fn is_radial(&self) -> bool {
        match self {
            Self::Unified(m) => m.radtan()[2..] == [0.0, 0.0],
            Self::PinholeRadtan(m) => m.radtan()[2..] == [0.0, 0.0],
            _ => true,
        }
    }
}

/// A camera of a closed-form model: the lens, its image size and the field of view it sees
/// (at most the model's).
#[derive(Debug, Clone, PartialEq)]
pub struct CentralCamera {
    pub lens: Lens,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The field of view the camera sees, degrees (at most the lens model's).
    pub max_fov_deg: f64,
}

impl CentralCamera {
    /// A camera of `lens` with `width x height` images seeing `max_fov_deg` (the model's
    /// widest when `None`).
    ///
    /// # Errors
    /// [`CameraError::Param`] for a zero image size or a field of view that is not positive
    /// or is wider than the model projects.
    pub fn new(
        lens: Lens,
        width: u32,
        height: u32,
        max_fov_deg: Option<f64>,
    ) -> Result<Self, CameraError> {
        let model_fov = lens.max_fov_deg();
        let bad = |param, message: String| Err(CameraError::param(lens.name(), param, message));
        if width == 0 || height == 0 {
            return bad(
                "image_size",
                format!("must be positive, got {height}x{width}"),
            );
        }
        let fov = max_fov_deg.unwrap_or(model_fov);
        if !(fov > 0.0 && fov <= model_fov + 1e-9) {
            return bad(
                "max_fov",
                format!(
                    "must lie in (0, {model_fov}] degrees (what the model projects), got {fov}"
                ),
            );
        }
        Ok(Self {
            lens,
            width,
            height,
            max_fov_deg: fov.min(model_fov),
        })
    }

    /// Half the field of view, radians.
    pub fn half_fov_rad(&self) -> f64 {
        self.max_fov_deg.to_radians() / 2.0
    }

    /// Whether a point lies within the field of view (angle from the optical axis at most
    /// half of it).
    fn sees(&self, p_cam: &Vector3<f64>) -> bool {
        let rho = (p_cam.x * p_cam.x + p_cam.y * p_cam.y).sqrt();
        rho.atan2(p_cam.z) <= self.half_fov_rad()
    }

    /// Projects a point of the camera frame; `None` outside the field of view.
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        if !self.sees(p_cam) {
            return None;
        }
        self.lens.project(p_cam)
    }

    /// [`Self::project`] of every point of `points` into `pixels` (same length), with the
    /// same result to the bit; points clearly inside or outside the field of view need no
    /// `atan2` to tell.
    pub fn project_many(&self, points: &[Vector3<f64>], pixels: &mut [Option<Pixel>]) {
        debug_assert_eq!(points.len(), pixels.len());
        const RUN: usize = 64;
        let half_fov = self.half_fov_rad();
        let cone = FovCone::new(half_fov);
        let mut seen = [Vector3::zeros(); RUN];
        let mut seen_at = [0usize; RUN];
        let mut projected = [None; RUN];
        for (points, pixels) in points.chunks(RUN).zip(pixels.chunks_mut(RUN)) {
            // The points the camera sees (`sees`, with the cone first), projected together.
            let mut n = 0;
            for (i, (p_cam, out)) in points.iter().zip(pixels.iter_mut()).enumerate() {
                let rho = (p_cam.x * p_cam.x + p_cam.y * p_cam.y).sqrt();
                let sees = cone
                    .side(rho, p_cam.z)
                    .unwrap_or_else(|| rho.atan2(p_cam.z) <= half_fov);
                *out = None;
                if sees {
                    (seen[n], seen_at[n]) = (*p_cam, i);
                    n += 1;
                }
            }
            self.lens.project_many(&seen[..n], &mut projected[..n]);
            for (&i, &px) in seen_at[..n].iter().zip(&projected[..n]) {
                pixels[i] = px;
            }
        }
    }

    /// The unit ray of a pixel; `None` outside the field of view.
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        self.lens.unproject(px).filter(|ray| self.sees(ray))
    }

    /// The same camera with both focal lengths multiplied by `scale`, the principal point and
    /// the field of view kept: a calibration whose focal length is off.
    ///
    /// # Errors
    /// [`CameraError::Param`] for a scale that makes a focal length not positive or not finite.
    pub fn with_focal_scaled(&self, scale: f64) -> Result<Self, CameraError> {
        let f = self.lens.focal();
        let focal = Focal::new(
            self.lens.name(),
            f.fx() * scale,
            f.fy() * scale,
            f.cx(),
            f.cy(),
        )?;
        Ok(Self {
            lens: self.lens.with_focal(focal),
            ..self.clone()
        })
    }

    /// The same camera with `height x width` images: the same rays (pixel centres map as
    /// `(p + 0.5) s - 0.5`).
    pub fn resized(&self, height: u32, width: u32) -> Self {
        let f = self.lens.focal();
        let (sc, sr) = (
            f64::from(width) / f64::from(self.width),
            f64::from(height) / f64::from(self.height),
        );
        let focal = Focal::scaled(&f, sc, sr);
        Self {
            lens: self.lens.with_focal(focal),
            width,
            height,
            max_fov_deg: self.max_fov_deg,
        }
    }

    /// `m(alpha)`: the distance from the principal point on the model's image plane (before
    /// the focal lengths) of a point at `alpha_rad` from the optical axis, for a radial lens.
    /// Beyond the model's domain (or at its very edge, where some projections are undefined)
    /// the value at 1e-9 rad inside the edge stands for it, so that tables spanning a little
    /// more than the field of view stay finite.
    pub fn plane_radius(&self, alpha_rad: f64) -> f64 {
        let f = self.lens.focal();
        let at = |a: f64| {
            self.lens
                .project(&Vector3::new(a.sin(), 0.0, a.cos()))
                .map(|px| (px.col - f.cx()) / f.fx())
        };
        let edge = self.lens.max_fov_deg().to_radians() / 2.0 - 1e-9;
        at(alpha_rad)
            .or_else(|| at(alpha_rad.min(edge)))
            .unwrap_or(f64::NAN)
    }
}
