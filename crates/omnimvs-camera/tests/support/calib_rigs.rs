//! Rigs for the calibration-file tests: one camera of each model a format states, with
//! non-trivial rotations and translations, and comparisons of intrinsics and poses.

use nalgebra::Isometry3;
use omnimvs_camera::{
    Camera, CameraModel, CentralCamera, DoubleSphere, ExtendedUnified, KannalaBrandt4, Lens,
    PinholeRadtan, Pose, Rig, Unified,
};

/// A camera of `lens` with `width x height` images, its model's widest field of view and the
/// pose `rvec`, `t_m`.
pub fn camera(
    id: u32,
    lens: Lens,
    width: u32,
    height: u32,
    rvec: [f64; 3],
    t_m: [f64; 3],
) -> Camera {
    let central = CentralCamera::new(lens, width, height, None).unwrap();
    Camera::new(
        id,
        format!("cam{id}"),
        CameraModel::Central(central),
        Pose { rvec, t_m },
        None,
    )
}

pub fn ds() -> Lens {
    Lens::DoubleSphere(
        DoubleSphere::new(158.286, 158.274, 254.961, 256.889, -0.172, 0.593).unwrap(),
    )
}

pub fn eucm() -> Lens {
    Lens::ExtendedUnified(
        ExtendedUnified::new(460.76, 459.12, 365.81, 249.33, 0.6123, 1.0871).unwrap(),
    )
}

pub fn kb4() -> Lens {
    Lens::KannalaBrandt4(
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
        .unwrap(),
    )
}

pub fn pinhole() -> Lens {
    Lens::PinholeRadtan(
        PinholeRadtan::new(458.654, 457.296, 367.215, 248.375, 0.0, 0.0, 0.0, 0.0).unwrap(),
    )
}

pub fn pinhole_radtan() -> Lens {
    Lens::PinholeRadtan(
        PinholeRadtan::new(
            458.654,
            457.296,
            367.215,
            248.375,
            -0.28340811,
            0.07395907,
            0.00019359,
            1.76187114e-05,
        )
        .unwrap(),
    )
}

pub fn ucm() -> Lens {
    Lens::Unified(Unified::new(764.3, 763.9, 641.7, 481.2, 1.3721).unwrap())
}

pub fn ucm_radtan() -> Lens {
    Lens::Unified(
        Unified::with_radtan(
            833.006,
            830.345,
            373.850,
            253.749,
            0.80065662,
            [-0.33518, 0.13211, 0.00055, 0.00057],
        )
        .unwrap(),
    )
}

/// Non-trivial poses, one per camera (angles well away from a half turn).
const POSES: [([f64; 3], [f64; 3]); 7] = [
    ([0.3, -1.2, 0.5], [0.12, -0.034, 0.056]),
    ([-0.8, 0.25, 1.9], [-0.2, 0.15, 0.01]),
    ([0.01, 2.2, -0.4], [0.0, 0.3, -0.25]),
    ([1.1, 0.7, -0.2], [0.45, -0.05, 0.0]),
    ([-0.05, -0.02, 0.03], [-0.11, -0.12, 0.13]),
    ([0.6, -0.6, 0.6], [0.02, 0.5, 0.3]),
    ([2.0, 0.4, 0.1], [0.33, 0.0, -0.07]),
];

/// A rig of `lenses`, each with its image size, posed by [`POSES`].
pub fn rig_of(first_id: u32, lenses: Vec<(Lens, u32, u32)>) -> Rig {
    Rig::new(
        lenses
            .into_iter()
            .zip(POSES)
            .enumerate()
            .map(|(i, ((lens, w, h), (rvec, t)))| camera(first_id + i as u32, lens, w, h, rvec, t))
            .collect(),
    )
}

/// Every model Basalt's `calibration.json` states.
pub fn basalt_rig() -> Rig {
    rig_of(
        0,
        vec![
            (ds(), 512, 512),
            (eucm(), 752, 480),
            (kb4(), 848, 800),
            (pinhole(), 752, 480),
            (ucm(), 1280, 960),
        ],
    )
}

/// Every model Kalibr's `camchain.yaml` states.
pub fn kalibr_rig() -> Rig {
    rig_of(
        0,
        vec![
            (pinhole_radtan(), 752, 480),
            (pinhole(), 640, 480),
            (kb4(), 848, 800),
            (ucm(), 1280, 960),
            (ucm_radtan(), 752, 480),
            (ds(), 512, 512),
            (eucm(), 752, 480),
        ],
    )
}

/// The lens of a closed-form camera.
pub fn lens_of(cam: &Camera) -> &Lens {
    match &cam.model {
        CameraModel::Central(c) => &c.lens,
        CameraModel::Ocam(_) => panic!("camera {} is OCamCalib", cam.id),
    }
}

/// A lens's model name and every parameter: focal step first, then the model's own.
pub fn params_of(lens: &Lens) -> (&'static str, Vec<f64>) {
    let f = lens.focal();
    let mut p = vec![f.fx(), f.fy(), f.cx(), f.cy()];
    match lens {
        Lens::DoubleSphere(m) => p.extend([m.xi(), m.alpha()]),
        Lens::ExtendedUnified(m) => p.extend([m.alpha(), m.beta()]),
        Lens::Unified(m) => p.extend([&[m.xi()][..], &m.radtan()].concat()),
        Lens::KannalaBrandt4(m) => p.extend(m.k()),
        Lens::PinholeRadtan(m) => p.extend(m.radtan()),
    }
    (lens.name(), p)
}

/// Asserts the same model and parameters within `rel` relative to each value (0: exact).
pub fn assert_same_intrinsics(a: &Camera, b: &Camera, rel: f64) {
    let ((na, pa), (nb, pb)) = (params_of(lens_of(a)), params_of(lens_of(b)));
    assert_eq!(na, nb, "camera {} vs {}", a.id, b.id);
    for (x, y) in pa.iter().zip(&pb) {
        assert!((x - y).abs() <= rel * x.abs(), "{na}: {pa:?} vs {pb:?}");
    }
    assert_eq!(
        (a.model.width(), a.model.height()),
        (b.model.width(), b.model.height())
    );
}

/// `cam_i_from_cam_j` of a rig.
pub fn relative(rig: &Rig, i: usize, j: usize) -> Isometry3<f64> {
    rig.cameras[i].rig_from_cam.inverse() * rig.cameras[j].rig_from_cam
}

/// Asserts two isometries agree: rotation angle and translation within `tol`.
pub fn assert_same_isometry(a: &Isometry3<f64>, b: &Isometry3<f64>, tol: f64) {
    let angle = a.rotation.angle_to(&b.rotation);
    let dt = (a.translation.vector - b.translation.vector).norm();
    assert!(
        angle < tol && dt < tol,
        "{a:?} vs {b:?}: {angle:e} rad, {dt:e} m"
    );
}

/// Asserts every relative pose of two rigs of the same size agrees within `tol`.
pub fn assert_same_relative_poses(a: &Rig, b: &Rig, tol: f64) {
    assert_eq!(a.len(), b.len());
    for i in 0..a.len() {
        for j in 0..a.len() {
            assert_same_isometry(&relative(a, i, j), &relative(b, i, j), tol);
        }
    }
}

/// Asserts two poses agree component by component (rotation vector and translation).
pub fn assert_same_pose(a: &Pose, b: &Pose, tol: f64) {
    for (x, y) in a.to_array().iter().zip(b.to_array()) {
        assert!((x - y).abs() < tol, "{a:?} vs {b:?}");
    }
}
