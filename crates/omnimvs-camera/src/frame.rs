//! The frame a rig's poses are expressed in, and a frame fitted to the cameras for rigs whose
//! calibration frame is not level with them.
//!
//! The sweep's spheres are centred at the rig frame's origin and its panorama's vertical axis
//! is the frame's y axis (FORMATS.md). A calibration tool's frame (Basalt's IMU, Kalibr's
//! first camera) may sit anywhere on the rig and be tilted; [`Rig::fitted_frame`] gives the
//! frame centred at the cameras' mean position with its y axis normal to the plane the
//! cameras span.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::{Camera, CameraError, Pose, Rig};

/// Which frame a rig's panoramas are expressed in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum FrameChoice {
    /// The frame of the calibration file's poses, as they are.
    #[default]
    Calibration,
    /// The frame fitted to the cameras ([`Rig::fitted_frame`]).
    Fitted,
}

impl FrameChoice {
    /// `calibration` or `fitted`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Calibration => "calibration",
            Self::Fitted => "fitted",
        }
    }
}

impl Rig {
    /// The frame fitted to the cameras, as `fitted_from_rig`: the origin at the mean of the
    /// optical centres, the y axis normal to the plane that fits them best (least squares),
    /// pointing to the same side as the rig frame's y axis, the x axis the rig frame's x axis
    /// projected onto that plane (its z axis when x is nearly normal to it), z = x cross y.
    ///
    /// # Errors
    /// [`CameraError::Frame`] for fewer than three cameras or cameras on one line, whose
    /// plane is undefined.
    pub fn fitted_frame(&self) -> Result<Isometry3<f64>, CameraError> {
        let centers: Vec<Vector3<f64>> = self
            .cameras
            .iter()
            .map(|c| c.center_in_rig().coords)
            .collect();
        if centers.len() < 3 {
            return Err(CameraError::Frame(format!(
                "a fitted frame needs at least three cameras to span a plane, the rig has {}",
                centers.len()
            )));
        }
        let mean = centers.iter().sum::<Vector3<f64>>() / centers.len() as f64;
        let scatter: Matrix3<f64> = centers
            .iter()
            .map(|c| (c - mean) * (c - mean).transpose())
            .sum();
        let eig = scatter.symmetric_eigen();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let (smallest, middle) = (eig.eigenvalues[order[0]], eig.eigenvalues[order[1]]);
        // Cameras on a line: the two smallest spreads are both (nearly) zero.
        if middle <= 1e-12 * eig.eigenvalues[order[2]].max(f64::MIN_POSITIVE) || middle <= 0.0 {
            return Err(CameraError::Frame(
                "a fitted frame needs cameras that span a plane; the rig's optical centres lie on one line"
                    .into(),
            ));
        }
        debug_assert!(smallest <= middle);
        let mut y = eig.eigenvectors.column(order[0]).into_owned().normalize();
        if y.y < 0.0 {
            y = -y;
        }
        let x_in_plane = |axis: Vector3<f64>| axis - y * y.dot(&axis);
        let mut x = x_in_plane(Vector3::x());
        if x.norm() < 1e-6 {
            x = x_in_plane(Vector3::z());
        }
        let x = x.normalize();
        let z = x.cross(&y);
        // Rows of rig_from_fitted's rotation transposed: fitted_from_rig maps rig axes onto
        // the fitted ones.
        let rig_from_fitted_rot =
            Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
        let rig_from_fitted = Isometry3::from_parts(
            Translation3::from(mean),
            UnitQuaternion::from_rotation_matrix(&rig_from_fitted_rot),
        );
        Ok(rig_from_fitted.inverse())
    }

    /// The rig expressed in the frame `choice` names, and `frame_from_rig` (the identity for
    /// [`FrameChoice::Calibration`], [`Self::fitted_frame`] for [`FrameChoice::Fitted`]).
    ///
    /// # Errors
    /// As [`Self::fitted_frame`], for the fitted frame.
    pub fn in_frame(self, choice: FrameChoice) -> Result<(Self, Isometry3<f64>), CameraError> {
        match choice {
            FrameChoice::Calibration => Ok((self, Isometry3::identity())),
            FrameChoice::Fitted => {
                let frame_from_rig = self.fitted_frame()?;
                Ok((self.re_expressed(&frame_from_rig), frame_from_rig))
            }
        }
    }

    /// The same rig with its poses expressed in another frame: `new_from_rig` maps points of
    /// the current rig frame into the new one. Intrinsics, ids, folders and masks are kept.
    pub fn re_expressed(&self, new_from_rig: &Isometry3<f64>) -> Self {
        let cameras = self
            .cameras
            .iter()
            .map(|c| {
                let new_from_cam = new_from_rig * c.rig_from_cam;
                Camera::new(
                    c.id,
                    c.img_dir.clone(),
                    c.model.clone(),
                    Pose::from_isometry(&new_from_cam),
                    c.invalid_mask.clone(),
                )
                .with_valid_mask(c.valid_mask.clone())
            })
            .collect();
        Rig::new(cameras)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;
    use crate::{CameraModel, CentralCamera, KannalaBrandt4, Lens};

    fn kb4() -> CameraModel {
        let lens = KannalaBrandt4::new(300.0, 300.0, 400.0, 400.0, 0.0, 0.0, 0.0, 0.0).unwrap();
        CameraModel::Central(
            CentralCamera::new(Lens::KannalaBrandt4(lens), 800, 800, None).unwrap(),
        )
    }

    /// Four cameras at 0.3 m around a centre, in a frame tilted and shifted against them.
    fn tilted_rig(rig_from_level: &Isometry3<f64>) -> Rig {
        let cameras = (0..4)
            .map(|i| {
                let yaw = std::f64::consts::FRAC_PI_2 * f64::from(i);
                let level_from_cam = Isometry3::new(
                    Vector3::new(0.3 * yaw.sin(), 0.0, 0.3 * yaw.cos()),
                    Vector3::new(0.0, yaw, 0.0),
                );
                Camera::new(
                    i,
                    format!("cam{i}"),
                    kb4(),
                    Pose::from_isometry(&(rig_from_level * level_from_cam)),
                    None,
                )
            })
            .collect();
        Rig::new(cameras)
    }

    #[test]
    fn the_fitted_frame_levels_a_tilted_rig() {
        let rig_from_level =
            Isometry3::new(Vector3::new(0.5, -0.2, 1.0), Vector3::new(0.2, 0.0, -0.1));
        let rig = tilted_rig(&rig_from_level);
        let fitted = rig.re_expressed(&rig.fitted_frame().unwrap());
        for cam in &fitted.cameras {
            let c = cam.center_in_rig();
            // Centred, in the plane y = 0, at 0.3 m from the centre.
            assert!(c.y.abs() < 1e-12, "{c:?}");
            assert!(
                ((c.x * c.x + c.z * c.z).sqrt() - 0.3).abs() < 1e-12,
                "{c:?}"
            );
        }
        let mean: Vector3<f64> = fitted
            .cameras
            .iter()
            .map(|c| c.center_in_rig().coords)
            .sum();
        assert!(mean.norm() < 1e-12);
        // Each camera's optical axis is level in the fitted frame.
        for cam in &fitted.cameras {
            let axis = cam.rig_from_cam.rotation * Vector3::z();
            assert!(axis.y.abs() < 1e-12, "{axis:?}");
        }
        // Re-expressing keeps the geometry: baselines unchanged.
        for (a, b) in rig.baselines_m().iter().zip(fitted.baselines_m()) {
            assert!((a.2 - b.2).abs() < 1e-12);
        }
    }

    #[test]
    fn a_level_centred_rig_is_its_own_fitted_frame() {
        let rig = tilted_rig(&Isometry3::identity());
        let f = rig.fitted_frame().unwrap();
        let p = f * Point3::new(0.1, 0.2, 0.3);
        assert!((p.coords - Vector3::new(0.1, 0.2, 0.3)).norm() < 1e-12);
    }

    #[test]
    fn two_cameras_or_a_line_have_no_fitted_frame() {
        let mut rig = tilted_rig(&Isometry3::identity());
        rig.cameras.truncate(2);
        assert!(matches!(rig.fitted_frame(), Err(CameraError::Frame(_))));
        let line = Rig::new(
            (0..3)
                .map(|i| {
                    let pose = Pose {
                        rvec: [0.0; 3],
                        t_m: [0.1 * f64::from(i), 0.0, 0.0],
                    };
                    Camera::new(i, format!("cam{i}"), kb4(), pose, None)
                })
                .collect(),
        );
        let err = line.fitted_frame().unwrap_err().to_string();
        assert!(err.contains("one line"), "{err}");
    }
}
