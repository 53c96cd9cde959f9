use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A camera-to-rig pose as the reference files store it: `X_rig = R(r) X_cam + t`
/// with `R(r)` the Rodrigues rotation of the rotation vector `r` (radians) and
/// `t` in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation vector (axis times angle), radians.
    pub rvec: [f64; 3],
    /// Translation, metres.
    pub t_m: [f64; 3],
}

impl Pose {
    /// The pose as `[rx, ry, rz, tx, ty, tz]` (the `config.yaml` layout).
    pub fn to_array(&self) -> [f64; 6] {
        let [rx, ry, rz] = self.rvec;
        let [tx, ty, tz] = self.t_m;
        [rx, ry, rz, tx, ty, tz]
    }

    /// `rig_from_cam` as an isometry.
    pub fn rig_from_cam(&self) -> Isometry3<f64> {
        isometry_from_pose(self)
    }

    /// The pose of an isometry `X_rig = rig_from_cam X_cam` (rotation vector of its rotation).
    pub fn from_isometry(rig_from_cam: &Isometry3<f64>) -> Self {
        let t = rig_from_cam.translation.vector;
        Self {
            rvec: rig_from_cam.rotation.scaled_axis().into(),
            t_m: [t.x, t.y, t.z],
        }
    }
}

/// The isometry `X_rig = R(r) X_cam + t` of a [`Pose`].
pub fn isometry_from_pose(pose: &Pose) -> Isometry3<f64> {
    let rot = Rotation3::new(Vector3::from(pose.rvec));
    Isometry3::from_parts(
        Translation3::from(Vector3::from(pose.t_m)),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turn_about_y_maps_camera_z_to_rig_x() {
        // Camera 2 of the published rig: ry = pi/2, t = (0.6, 0, 0).
        let pose = Pose {
            rvec: [0.0, std::f64::consts::FRAC_PI_2, 0.0],
            t_m: [0.6, 0.0, 0.0],
        };
        let rig_from_cam = pose.rig_from_cam();
        let p = rig_from_cam * nalgebra::Point3::new(0.0, 0.0, 1.0);
        assert!((p.coords - Vector3::new(1.6, 0.0, 0.0)).norm() < 1e-12);
    }
}
