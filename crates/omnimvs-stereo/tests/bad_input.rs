#![allow(clippy::unwrap_used, clippy::expect_used)]
//! Bad input gets a clear error, never a panic.

mod support;

use omnimvs_camera::{Rig, ValidityMask};
use omnimvs_core::GrayImage;
use omnimvs_stereo::{SgmParams, SphericalStereo, StereoError};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use support::scenes::published_rig;

fn grid() -> EquirectGrid {
    EquirectGrid::new(16, 64, 45.0).unwrap()
}

fn hyps(n: usize) -> InvDepthHypotheses {
    InvDepthHypotheses {
        count: n,
        min_depth_m: 1.0,
    }
}

fn images(rig: &Rig) -> Vec<GrayImage> {
    rig.cameras
        .iter()
        .map(|c| GrayImage::zeros(c.model.width() as usize, c.model.height() as usize))
        .collect()
}

#[test]
fn fewer_than_two_cameras() {
    let mut rig = published_rig(0.1);
    rig.cameras.truncate(1);
    let e = SphericalStereo::new(&rig, grid(), hyps(8), SgmParams::default()).unwrap_err();
    assert!(matches!(e, StereoError::TooFewCameras { found: 1 }));
    assert!(e.to_string().contains("at least two"), "{e}");
}

#[test]
fn odd_or_tiny_ndepth() {
    let rig = published_rig(0.1);
    for n in [0, 1, 7] {
        let e = SphericalStereo::new(&rig, grid(), hyps(n), SgmParams::default()).unwrap_err();
        assert!(matches!(e, StereoError::NDepth { .. }), "{n}: {e}");
        assert!(e.to_string().contains("even number of at least 2"), "{e}");
    }
}

#[test]
fn p2_below_p1() {
    let rig = published_rig(0.1);
    let params = SgmParams {
        p1: 0.5,
        p2: 0.2,
        ..SgmParams::default()
    };
    let e = SphericalStereo::new(&rig, grid(), hyps(8), params).unwrap_err();
    assert!(matches!(e, StereoError::Penalties { .. }));
    assert!(e.to_string().contains("P2 >= P1"), "{e}");
}

#[test]
fn mismatched_images_and_masks() {
    let rig = published_rig(0.1);
    let stereo = SphericalStereo::new(&rig, grid(), hyps(8), SgmParams::default()).unwrap();
    let mut imgs = images(&rig);
    imgs[2] = GrayImage::zeros(10, 10);
    let e = stereo.compute(&imgs, None).unwrap_err();
    assert!(
        matches!(e, StereoError::SizeMismatch { camera: 3, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("camera 3 image is 10x10"), "{e}");

    let mut imgs = images(&rig);
    imgs.pop();
    let e = stereo.compute(&imgs, None).unwrap_err();
    assert!(
        matches!(
            e,
            StereoError::CountMismatch {
                expected: 4,
                found: 3,
                ..
            }
        ),
        "{e}"
    );

    let imgs = images(&rig);
    let mut masks: Vec<ValidityMask> = rig
        .cameras
        .iter()
        .map(|c| ValidityMask::from_fov(&c.model))
        .collect();
    masks[0] = ValidityMask {
        width: 3,
        height: 3,
        valid: vec![true; 9],
    };
    let e = stereo.compute(&imgs, Some(&masks)).unwrap_err();
    assert!(
        matches!(e, StereoError::SizeMismatch { camera: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("validity mask"), "{e}");
    // Blank images are not an error: every cost is uninformative.
    masks[0] = ValidityMask::from_fov(&rig.cameras[0].model);
    let out = stereo.compute(&imgs, Some(&masks)).unwrap();
    assert!(out.index.index.iter().all(|n| n.is_finite()));
}
