#![allow(clippy::unwrap_used, clippy::expect_used)]
//! `CameraModel::project_many` gives `project`'s results to the bit, for every model with a
//! batched path (OCamCalib, and closed-form cameras with a narrower field of view than their
//! lens: double sphere, Kannala-Brandt) and for one without (unified), on points in every
//! direction, at every distance, close to the edge of the field of view and on the axis.

use omnimvs_camera::nalgebra::Vector3;
use omnimvs_camera::{
    CameraModel, CentralCamera, DoubleSphere, KannalaBrandt4, Lens, OcamModel, Pixel, Unified,
};

#[path = "support/sunny_cam1.rs"]
mod sunny;

/// The models compared: OCamCalib with and without an affine shear, and closed-form lenses
/// seeing 220 degrees (the lens's own limit wider) or their whole domain.
fn models() -> Vec<CameraModel> {
    let mut sheared: OcamModel = sunny::sunny_cam1();
    (sheared.c, sheared.d, sheared.e) = (1.0003, -0.033, 0.0327);
    let ds = Lens::DoubleSphere(DoubleSphere::new(177.0, 178.0, 399.5, 383.5, -0.2, 0.6).unwrap());
    let kb4 = Lens::KannalaBrandt4(
        KannalaBrandt4::new(200.0, 201.0, 399.5, 383.5, -0.01, 0.002, 0.0, 0.0).unwrap(),
    );
    let ucm = Lens::Unified(Unified::new(300.0, 300.0, 399.5, 383.5, 0.9).unwrap());
    let central = |lens: &Lens, fov| {
        CameraModel::Central(CentralCamera::new(lens.clone(), 800, 768, fov).unwrap())
    };
    vec![
        CameraModel::Ocam(sunny::sunny_cam1()),
        CameraModel::Ocam(sheared),
        central(&ds, Some(220.0)),
        central(&ds, None),
        central(&kb4, Some(220.0)),
        central(&kb4, None),
        central(&ucm, Some(190.0)),
    ]
}

/// Points at angles from the optical axis over the whole sphere, finely around the edge of
/// a 220-degree field of view and of each model's own, at several azimuths and distances;
/// the origin and points on the axis.
fn points(edges_deg: &[f64]) -> Vec<Vector3<f64>> {
    let mut alphas: Vec<f64> = (0..=1800).map(|k| f64::from(k) * 0.1).collect();
    for edge in edges_deg {
        alphas.extend((-300..=300).map(|k| edge + f64::from(k) * 1e-8));
        alphas.extend((-30..=30).map(|k| edge + f64::from(k) * 1e-13));
    }
    let mut points = vec![Vector3::zeros(), Vector3::new(0.0, 0.0, -2.0)];
    for alpha in alphas.iter().map(|a| a.to_radians()) {
        for azimuth in [0.0f64, 0.3, 1.9, 3.1, 4.4] {
            for dist in [1e-3, 1.7, 4.5e15] {
                points.push(
                    dist * Vector3::new(
                        alpha.sin() * azimuth.cos(),
                        alpha.sin() * azimuth.sin(),
                        alpha.cos(),
                    ),
                );
            }
        }
    }
    points
}

fn bits(px: Option<Pixel>) -> Option<(u64, u64)> {
    px.map(|p| (p.col.to_bits(), p.row.to_bits()))
}

#[test]
fn project_many_equals_project_to_the_bit() {
    for model in models() {
        let points = points(&[110.0, model.max_fov_deg() / 2.0]);
        let mut many = vec![None; points.len()];
        model.project_many(&points, &mut many);
        let (mut inside, mut outside) = (0, 0);
        for (p, got) in points.iter().zip(&many) {
            let want = model.project(p);
            assert_eq!(bits(*got), bits(want), "{} at {p:?}", model.name());
            if want.is_some() {
                inside += 1
            } else {
                outside += 1
            }
        }
        assert!(
            inside > 1000 && outside > 1000,
            "{}: {inside} {outside}",
            model.name()
        );
        // Any length, not only whole batches.
        let mut few = vec![None; 13];
        model.project_many(&points[5..18], &mut few);
        let few: Vec<_> = few.into_iter().map(bits).collect();
        let want: Vec<_> = many[5..18].iter().copied().map(bits).collect();
        assert_eq!(few, want, "{}", model.name());
    }
}
