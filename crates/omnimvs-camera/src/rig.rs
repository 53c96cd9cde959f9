use std::fmt::Write as _;

use nalgebra::{Isometry3, Point3, Vector3};

use crate::{CameraError, CameraModel, Pixel, Pose};

/// One camera of a rig: intrinsics, pose and where its images live.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// `cam_id` of the configuration (1-based in the published files).
    pub id: u32,
    /// Folder of this camera's images, relative to the dataset folder.
    pub img_dir: String,
    /// Intrinsic model.
    pub model: CameraModel,
    /// Camera-to-rig pose as stored in the files.
    pub pose: Pose,
    /// `X_rig = rig_from_cam * X_cam`, derived from [`Self::pose`].
    pub rig_from_cam: Isometry3<f64>,
    /// File name (relative to the dataset folder) of the PNG marking pixels to
    /// ignore (non-zero = invalid), if the configuration names one.
    pub invalid_mask: Option<String>,
    /// File name (relative to the dataset folder) of an image marking the pixels that carry
    /// scene content (non-zero = valid), such as `cam0/mask.png` beside the camera's images.
    pub valid_mask: Option<String>,
}

impl Camera {
    /// Builds a camera, deriving `rig_from_cam` from the pose.
    pub fn new(
        id: u32,
        img_dir: impl Into<String>,
        model: CameraModel,
        pose: Pose,
        invalid_mask: Option<String>,
    ) -> Self {
        Self {
            id,
            img_dir: img_dir.into(),
            model,
            pose,
            rig_from_cam: pose.rig_from_cam(),
            invalid_mask,
            valid_mask: None,
        }
    }

    /// The same camera with a validity mask image (non-zero = valid), relative to the dataset
    /// folder.
    pub fn with_valid_mask(self, valid_mask: Option<String>) -> Self {
        Self { valid_mask, ..self }
    }

    /// Projects a point in the rig frame (metres) to a pixel of this camera;
    /// `None` outside the field of view.
    pub fn project_rig(&self, p_rig: &Point3<f64>) -> Option<Pixel> {
        let p_cam = self.rig_from_cam.inverse_transform_point(p_rig);
        self.model.project(&p_cam.coords)
    }

    /// The unit ray of a pixel, expressed in the rig frame (a direction: it
    /// starts at [`Self::center_in_rig`]); `None` outside the field of view.
    pub fn ray_in_rig(&self, px: Pixel) -> Option<Vector3<f64>> {
        let ray_in_cam = self.model.unproject(px)?;
        Some(self.rig_from_cam.rotation * ray_in_cam)
    }

    /// The optical centre in the rig frame, metres.
    pub fn center_in_rig(&self) -> Point3<f64> {
        Point3::from(self.rig_from_cam.translation.vector)
    }
}

/// A rig of any number of fisheye cameras, in the order of the configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    pub cameras: Vec<Camera>,
}

impl Rig {
    pub fn new(cameras: Vec<Camera>) -> Self {
        Self { cameras }
    }

    /// Number of cameras.
    pub fn len(&self) -> usize {
        self.cameras.len()
    }

    /// Whether the rig has no camera.
    pub fn is_empty(&self) -> bool {
        self.cameras.is_empty()
    }

    /// Distances in metres between the optical centres of every pair `(i, j)`,
    /// `i < j`.
    pub fn baselines_m(&self) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        for (i, a) in self.cameras.iter().enumerate() {
            for (j, b) in self.cameras.iter().enumerate().skip(i + 1) {
                out.push((i, j, (a.center_in_rig() - b.center_in_rig()).norm()));
            }
        }
        out
    }

    /// Checks that every camera sees part of the scene: some pixel of its image (on a 33x33 grid
    /// and the centre) unprojects inside its field of view. A principal point far outside the
    /// image, or a field of view that no pixel reaches, leaves a camera blind.
    ///
    /// # Errors
    /// [`CameraError::Field`] naming `path` and the camera's field (`field_of(index)`).
    pub fn check_cameras_see(
        &self,
        path: &std::path::Path,
        field_of: impl Fn(usize) -> String,
    ) -> Result<(), CameraError> {
        const STEPS: u32 = 32;
        for (i, cam) in self.cameras.iter().enumerate() {
            let m = &cam.model;
            let (w, h) = (f64::from(m.width()), f64::from(m.height()));
            let centre = Pixel::new((w - 1.0) / 2.0, (h - 1.0) / 2.0);
            let sees = m.unproject(centre).is_some()
                || (0..=STEPS).any(|r| {
                    (0..=STEPS).any(|c| {
                        let px = Pixel::new(
                            (w - 1.0) * f64::from(c) / f64::from(STEPS),
                            (h - 1.0) * f64::from(r) / f64::from(STEPS),
                        );
                        m.unproject(px).is_some()
                    })
                });
            if !sees {
                return Err(CameraError::field(
                    path,
                    field_of(i),
                    format!(
                        "no pixel of the {}x{} image lies in the {} model's field of view ({:.1} degrees): is the principal point inside the image, and are the intrinsics those of this resolution?",
                        m.width(),
                        m.height(),
                        m.name(),
                        m.max_fov_deg()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// A canonical text of every geometric parameter of the rig (intrinsics,
    /// image sizes, FOV and poses, at full precision). Two rigs with the same
    /// text give the same lookup tables; used as a cache key.
    pub fn content_key(&self) -> String {
        let mut s = String::new();
        for cam in &self.cameras {
            let CameraModel::Ocam(m) = &cam.model else {
                // The closed-form models: every parameter at full precision (`{:?}`).
                let _ = write!(
                    s,
                    "{:?};fov={:?};pose={:?}|",
                    cam.model,
                    cam.model.max_fov_deg(),
                    cam.pose.to_array()
                );
                continue;
            };
            let _ = write!(
                s,
                "ocam;poly={:?};inv={:?};center={:?},{:?};affine={:?},{:?},{:?};size={}x{};fov={:?};pose={:?}|",
                m.poly,
                m.inv_poly,
                m.center_row,
                m.center_col,
                m.c,
                m.d,
                m.e,
                m.width,
                m.height,
                m.max_fov_deg,
                cam.pose.to_array()
            );
        }
        s
    }
}
