#![allow(clippy::unwrap_used, clippy::expect_used)]
//! Random rigs (`--rig random:SEED`) stay inside the ranges they promise: camera counts,
//! baselines, lens models, fields of view that fit their images, tilts, and calibration
//! errors of the stated size in about half of them; the same seed gives the same rig.

use omnimvs_camera::nalgebra::Vector3;
use omnimvs_camera::{Pixel, Rig};
use omnimvs_synth::random_rig::{RandomRigSpec, parse_random_rig, random_rig};

const SEEDS: u64 = 300;

fn horizontal_radius(rig: &Rig, cam: usize) -> f64 {
    let c = rig.cameras[cam].center_in_rig();
    c.x.hypot(c.z)
}

#[test]
fn random_rigs_stay_in_their_ranges() {
    let spec = RandomRigSpec::default();
    let mut counts = std::collections::BTreeMap::new();
    let mut models = std::collections::BTreeMap::new();
    let mut with_error = 0;
    for seed in 0..SEEDS {
        let source = random_rig(seed, &spec).unwrap();
        let rig = &source.rig;
        let n = rig.len();
        assert!((2..=8).contains(&n), "seed {seed}: {n} cameras");
        *counts.entry(n).or_insert(0) += 1;
        *models.entry(rig.cameras[0].model.name()).or_insert(0) += 1;
        // On a ring: neighbours at 2 pi / n are 2 r sin(pi / n) apart, in the promised range.
        let r = horizontal_radius(rig, 0);
        let baseline = 2.0 * r * (std::f64::consts::PI / n as f64).sin();
        assert!(
            (0.05 - 1e-9..=0.6 + 1e-9).contains(&baseline),
            "seed {seed}: {baseline}"
        );
        assert!((0.3..=1.65).contains(&source.min_depth_m));
        for (i, camera) in rig.cameras.iter().enumerate() {
            assert!((horizontal_radius(rig, i) - r).abs() < 1e-9);
            let fov = camera.model.max_fov_deg();
            assert!((180.0..=250.0).contains(&fov), "seed {seed}: FOV {fov}");
            // The edge of the field of view lies inside the image, where the lens is still
            // defined.
            let half = (fov / 2.0 - 1e-6).to_radians();
            let edge = Vector3::new(half.sin(), 0.0, half.cos());
            let Pixel { col, row } = camera.model.project(&edge).expect("the edge projects");
            let (w, h) = (
                f64::from(camera.model.width()),
                f64::from(camera.model.height()),
            );
            assert!(col > 0.0 && col < w && row > 0.0 && row < h, "seed {seed}");
            // Facing outwards, tilted at most 15 degrees (pitch and roll combined: 21).
            let axis = camera.rig_from_cam.rotation * Vector3::z();
            let outwards = camera.center_in_rig().coords;
            let outwards = Vector3::new(outwards.x, 0.0, outwards.z).normalize();
            let tilt = axis.y.asin().to_degrees().abs();
            assert!(tilt <= 15.0 + 1e-9, "seed {seed}: tilt {tilt}");
            assert!(axis.dot(&outwards) > 0.5, "seed {seed}: faces inwards");
        }
        if let Some(stated) = &source.stated {
            with_error += 1;
            for (truth, told) in rig.cameras.iter().zip(&stated.cameras) {
                let error = truth.rig_from_cam.inverse() * told.rig_from_cam;
                assert!(error.rotation.angle().to_degrees() <= 0.2 + 1e-9);
                assert!(error.translation.vector.norm() <= 0.002 + 1e-12);
                let (a, b) = (truth.model.width(), told.model.width());
                assert_eq!(a, b);
            }
            assert_ne!(stated, rig);
        }
    }
    println!("cameras {counts:?}, models {models:?}, with a calibration error {with_error}");
    assert_eq!(counts.len(), 7, "{counts:?}");
    assert_eq!(models.len(), 4, "{models:?}");
    assert!((SEEDS / 3..SEEDS * 2 / 3).contains(&with_error));
}

#[test]
fn the_same_seed_gives_the_same_rig() {
    let spec = RandomRigSpec::default();
    assert_eq!(
        random_rig(42, &spec).unwrap(),
        random_rig(42, &spec).unwrap()
    );
    assert_ne!(
        random_rig(42, &spec).unwrap(),
        random_rig(43, &spec).unwrap()
    );
}

#[test]
fn random_rig_names_are_checked() {
    assert_eq!(parse_random_rig("random:17").unwrap(), Some(17));
    assert_eq!(parse_random_rig("sunny").unwrap(), None);
    let err = parse_random_rig("random:seven").unwrap_err().to_string();
    assert!(err.contains("random:SEED"), "{err}");
    let bad = RandomRigSpec {
        cameras: (1, 4),
        ..RandomRigSpec::default()
    };
    assert!(random_rig(1, &bad).is_err());
}
