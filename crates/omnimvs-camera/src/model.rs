use nalgebra::Vector3;

use crate::{CentralCamera, OcamModel, Pixel, RadialProjection};

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

    /// A short name of the model, as written in `config.yaml`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Ocam(_) => "ocam",
            Self::Central(c) => c.lens.name(),
        }
    }
}
