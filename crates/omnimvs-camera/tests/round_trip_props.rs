#![allow(clippy::unwrap_used, clippy::expect_used)]
//! Property tests of the camera model: a ray projected and unprojected comes back, a pixel
//! unprojected and projected comes back, and projection ignores the distance along the ray.
//! The model is camera 1 of the published "Sunny" rig (`sunny_single/config.yaml`), written
//! out here so that the test needs no data; its fitted inverse polynomial agrees with the
//! forward one to 0.0056 px / 0.0017 deg (`real_samples.rs`), hence the bounds.

use omnimvs_camera::nalgebra::Vector3;
use omnimvs_camera::{CameraModel, OcamModel, Pixel};
use proptest::prelude::*;

#[path = "support/sunny_cam1.rs"]
mod sunny;

/// Camera 1 of the published "Sunny" rig, as a camera model.
fn sunny_cam1() -> CameraModel {
    CameraModel::Ocam(sunny::sunny_cam1())
}

/// The unit ray at `alpha` from the optical axis (+z) and azimuth `azimuth`, radians.
fn ray(alpha: f64, azimuth: f64) -> Vector3<f64> {
    Vector3::new(
        alpha.sin() * azimuth.cos(),
        alpha.sin() * azimuth.sin(),
        alpha.cos(),
    )
}

fn distance_px(a: Pixel, b: Pixel) -> f64 {
    ((a.col - b.col).powi(2) + (a.row - b.row).powi(2)).sqrt()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// ray -> pixel -> ray -> pixel, anywhere inside the FOV (just short of its edge, where
    /// the two fitted polynomials may disagree on whether a point is inside).
    #[test]
    fn ray_pixel_ray(fraction in 0.0..0.99f64, azimuth in -std::f64::consts::PI..std::f64::consts::PI, depth_m in 0.05..500.0f64) {
        let model = sunny_cam1();
        let alpha = fraction * model.half_fov_rad();
        let ray_in_cam = ray(alpha, azimuth);
        let px = model.project(&(ray_in_cam * depth_m)).expect("inside the FOV");
        prop_assert!(model.contains(px), "{px:?} outside the image");
        let back = model.unproject(px).expect("a projected pixel unprojects");
        prop_assert!((back.norm() - 1.0).abs() < 1e-9, "not a unit ray: {back:?}");
        prop_assert!(back.angle(&ray_in_cam).to_degrees() < 0.003, "angle {} deg", back.angle(&ray_in_cam).to_degrees());
        let px2 = model.project(&back).expect("the ray back is inside the FOV");
        prop_assert!(distance_px(px, px2) < 0.01, "{px:?} -> {px2:?}");
    }

    /// pixel -> ray -> pixel for every pixel that unprojects (inside the image circle).
    #[test]
    fn pixel_ray_pixel(col in 0.0..800.0f64, row in 0.0..768.0f64) {
        let model = sunny_cam1();
        let px = Pixel::new(col, row);
        if let Some(ray_in_cam) = model.unproject(px) {
            let angle = ray_in_cam.angle(&Vector3::z());
            // Just inside the edge the forward model may call the ray outside the FOV.
            prop_assume!(angle < 0.99 * model.half_fov_rad());
            let back = model.project(&ray_in_cam).expect("inside the FOV");
            prop_assert!(distance_px(px, back) < 0.01, "{px:?} -> {back:?}");
        }
    }

    /// A point and any positive multiple of it project to the same pixel; a point behind
    /// the lens beyond the FOV does not project.
    #[test]
    fn projection_ignores_distance(fraction in 0.0..0.99f64, azimuth in -3.0..3.0f64, scale in 0.01..1000.0f64) {
        let model = sunny_cam1();
        let p = ray(fraction * model.half_fov_rad(), azimuth) * 2.0;
        let (a, b) = (model.project(&p).unwrap(), model.project(&(p * scale)).unwrap());
        prop_assert!(distance_px(a, b) < 1e-6, "{a:?} vs {b:?}");
        let outside = ray(model.half_fov_rad() + 0.02 + fraction * 0.5, azimuth);
        prop_assert!(model.project(&outside).is_none());
    }
}
