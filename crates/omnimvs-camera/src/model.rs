use nalgebra::Vector3;

use crate::{CentralCamera, OcamModel, Pixel, RadialProjection};

/// The angle from the optical axis out to which [`CameraModel::angular_resolution`] measures
/// a camera's pixels per radian: inside the field of view of every fisheye lens omnimvs takes.
pub const RESOLUTION_ANGLE_DEG: f64 = 80.0;

/// A camera's intrinsic model. An enum rather than a trait object so that a
/// rig stays `Clone + PartialEq + Send + Sync` and can be hashed for caching.
#[derive(Debug, Clone, PartialEq)]
pub enum CameraModel {
    /// OCamCalib (`model: ocam` in `config.yaml`).
    Ocam(OcamModel),
    /// A closed-form model (`model: ds | eucm | ucm | kb4 | pinhole-radtan`).
    Central(CentralCamera),
}

impl CameraModel {
    /// Projects a point in the camera frame to a pixel; `None` outside the FOV.
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        match self {
            Self::Ocam(m) => m.project(p_cam),
            Self::Central(c) => c.project(p_cam),
        }
    }

    /// [`Self::project`] of every point of `points` into `pixels` (same length), with the
    /// same result to the bit, faster for many points (tables of projections).
    pub fn project_many(&self, points: &[Vector3<f64>], pixels: &mut [Option<Pixel>]) {
        debug_assert_eq!(points.len(), pixels.len());
        match self {
            Self::Ocam(m) => m.project_many(points, pixels),
            Self::Central(c) => c.project_many(points, pixels),
        }
    }

    /// The unit ray (camera frame) of a pixel; `None` outside the FOV.
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        match self {
            Self::Ocam(m) => m.unproject(px),
            Self::Central(c) => c.unproject(px),
        }
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        match self {
            Self::Ocam(m) => m.width,
            Self::Central(c) => c.width,
        }
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        match self {
            Self::Ocam(m) => m.height,
            Self::Central(c) => c.height,
        }
    }

    /// Full field of view, degrees.
    pub fn max_fov_deg(&self) -> f64 {
        match self {
            Self::Ocam(m) => m.max_fov_deg,
            Self::Central(c) => c.max_fov_deg,
        }
    }

    /// Half the field of view, radians: the largest angle from the optical
    /// axis that the camera sees.
    pub fn half_fov_rad(&self) -> f64 {
        match self {
            Self::Ocam(m) => m.half_fov_rad(),
            Self::Central(c) => c.half_fov_rad(),
        }
    }

    /// The same camera with its images resized to `height x width` pixels:
    /// the same rays at the new resolution (pixel centres map as
    /// `(p + 0.5) * s - 0.5`). Sizes must be positive.
    pub fn resized(&self, height: u32, width: u32) -> Self {
        debug_assert!(height > 0 && width > 0);
        match self {
            Self::Ocam(m) => Self::Ocam(m.resized(height, width)),
            Self::Central(c) => Self::Central(c.resized(height, width)),
        }
    }

    /// The projection as a radial function of the angle from the optical axis
    /// and an affine map, for projectors that tabulate it; `None` for a lens with tangential
    /// distortion, whose projection is not radial.
    pub fn radial_projection(&self) -> Option<RadialProjection> {
        match self {
            Self::Ocam(m) => Some(RadialProjection::ocam(m)),
            Self::Central(c) => c.lens.is_radial().then(|| RadialProjection::central(c)),
        }
    }

    /// Whether a pixel position lies inside the image rectangle.
    pub fn contains(&self, px: Pixel) -> bool {
        match self {
            Self::Ocam(m) => m.contains(px),
            Self::Central(c) => {
                px.col >= 0.0
                    && px.row >= 0.0
                    && px.col <= f64::from(c.width) - 1.0
                    && px.row <= f64::from(c.height) - 1.0
            }
        }
    }

    /// The image's mean angular resolution out to `angle_rad` from the optical axis, pixels
    /// per radian: the distance from the axis's pixel to the pixels of the rays at that angle
    /// (at eight azimuths), divided by the angle. For an equidistant lens it is the focal
    /// length; it lets images of different lenses and sizes be brought to one angular
    /// resolution. `None` when the camera does not see that angle all around.
    pub fn pixels_per_radian(&self, angle_rad: f64) -> Option<f64> {
        let centre = Pixel {
            col: (f64::from(self.width()) - 1.0) / 2.0,
            row: (f64::from(self.height()) - 1.0) / 2.0,
        };
        let axis = self.unproject(centre)?.normalize();
        // Two directions across the axis.
        let helper = if axis.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = axis.cross(&helper).normalize();
        let v = axis.cross(&u);
        let at_axis = self.project(&axis)?;
        let mut sum = 0.0;
        const AZIMUTHS: usize = 8;
        for k in 0..AZIMUTHS {
            let phi = std::f64::consts::TAU * k as f64 / AZIMUTHS as f64;
            let ray = axis * angle_rad.cos() + (u * phi.cos() + v * phi.sin()) * angle_rad.sin();
            let px = self.project(&ray)?;
            sum += (px.col - at_axis.col).hypot(px.row - at_axis.row);
        }
        Some(sum / AZIMUTHS as f64 / angle_rad)
    }

    /// [`Self::pixels_per_radian`] out to [`RESOLUTION_ANGLE_DEG`]: the measure the network's
    /// input size goes by.
    pub fn angular_resolution(&self) -> Option<f64> {
        self.pixels_per_radian(RESOLUTION_ANGLE_DEG.to_radians())
    }

    /// A short name of the model, as written in `config.yaml`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Ocam(_) => "ocam",
            Self::Central(c) => c.lens.name(),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::{KannalaBrandt4, Lens};

    #[test]
    fn an_equidistant_lens_has_its_focal_length_as_angular_resolution_at_every_size() {
        let lens = KannalaBrandt4::new(250.0, 250.0, 399.5, 399.5, 0.0, 0.0, 0.0, 0.0).unwrap();
        let camera = CameraModel::Central(
            CentralCamera::new(Lens::KannalaBrandt4(lens), 800, 800, Some(220.0)).unwrap(),
        );
        let ppr = camera.pixels_per_radian(80f64.to_radians()).unwrap();
        assert!((ppr - 250.0).abs() < 1e-6, "{ppr}");
        let half = camera.resized(400, 400);
        let ppr = half.pixels_per_radian(80f64.to_radians()).unwrap();
        assert!((ppr - 125.0).abs() < 1e-6, "{ppr}");
        // An angle beyond the field of view has no answer.
        assert_eq!(camera.pixels_per_radian(115f64.to_radians()), None);
    }
}
