#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The classical method behind the workspace's one depth interface: the same maps as the
//! pipeline, on its sweep, with its stages reported to an observer that asks for them.

mod support;

use omnimvs_data::{DepthEstimator, StageTimes};
use omnimvs_stereo::{SgmEstimator, SgmParams, SphericalStereo};
use omnimvs_sweep::SweepSpec;
use support::scenes::{Rendered, published_rig, textured_sphere};

#[test]
fn sgm_estimator_gives_the_pipeline_maps_and_its_stages() {
    let rig = published_rig(0.25);
    let spec = SweepSpec::from_sizes(32, 128, 45.0, 32, 1.0).unwrap();
    let frame = Rendered::new(&textured_sphere(4.0, 3), &rig);
    let stereo =
        SphericalStereo::new(&rig, spec.grid, spec.hypotheses, SgmParams::default()).unwrap();
    let want = stereo.compute(&frame.images, None).unwrap();

    let estimator: Box<dyn DepthEstimator> =
        Box::new(SgmEstimator::new(&rig, None, spec, SgmParams::default()).unwrap());
    assert_eq!(estimator.name(), "ZNCC+SGM");
    assert_eq!(estimator.spec(), &spec);
    let mut times = StageTimes::default();
    let est = estimator
        .estimate_observed(&frame.images, &mut times)
        .unwrap();
    assert_eq!(est.spec, spec);
    assert_eq!(est.index, want.index.index);
    assert_eq!(est.inv_depth, want.inv_depth);
    assert_eq!(est.confidence.as_deref(), Some(&want.index.confidence[..]));
    assert!(est.entropy.is_none());
    let names: Vec<&str> = times.stages.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        ["prepare", "warp", "cost", "aggregation", "wta", "total"]
    );
    assert!(times.get("total") >= times.get("cost"));

    // A wrong number of images is the implementation's error, kept inside.
    let err = estimator.estimate(&frame.images[..2]).unwrap_err();
    assert!(
        err.downcast_ref::<omnimvs_stereo::StereoError>().is_some(),
        "{err}"
    );
}

#[test]
fn masks_must_match_the_rig() {
    let rig = published_rig(0.25);
    let spec = SweepSpec::from_sizes(32, 128, 45.0, 32, 1.0).unwrap();
    let masks = vec![omnimvs_camera::ValidityMask::from_fov(
        &rig.cameras[0].model,
    )];
    assert!(SgmEstimator::new(&rig, Some(masks), spec, SgmParams::default()).is_err());
}
