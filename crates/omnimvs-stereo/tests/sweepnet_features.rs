#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The SweepNet-style cost's window features are the ZNCC cost's own numbers: a head that
//! averages `(1 - zncc) / 2` over the complete pairs rebuilds the ZNCC cost volume, and a
//! learned head changes the method's name and its answer.

mod support;

use std::sync::Arc;

use omnimvs_stereo::sweepnet::{FeatureLayout, FeatureSpec, SweepCostHead};
use omnimvs_stereo::{LearnedCost, Mlp, SgmParams, SphericalStereo, SweepStep};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use support::scenes::{Rendered, published_rig, room};

/// The mean pair cost of ZNCC, written as a head over the features of 9x9 windows (and 5x5
/// ones, unused).
#[derive(Debug)]
struct ZnccMean(FeatureLayout, FeatureSpec);

impl SweepCostHead for ZnccMean {
    fn method_name(&self) -> &str {
        "ZNCC as a head"
    }
    fn input_dim(&self) -> usize {
        self.0.dim()
    }
    fn features(&self) -> &FeatureSpec {
        &self.1
    }
    fn costs(&self, features: &[f32], out: &mut [f32]) {
        let l = self.0;
        for (f, o) in features.chunks_exact(l.dim()).zip(out) {
            *o = l.zncc_cost(f);
        }
    }
}

#[test]
fn zncc_head_rebuilds_the_zncc_cost_volume() {
    let rig = published_rig(0.25);
    let grid = EquirectGrid::new(40, 160, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(16, 1.0).unwrap();
    let frame = Rendered::new(&room(&rig, 11), &rig);
    let stereo = SphericalStereo::new(&rig, grid, hyps, SgmParams::default()).unwrap();
    let (zncc, _) = stereo.cost_volume(&frame.images, None).unwrap();
    let spec = FeatureSpec {
        radii: vec![4, 2],
        shifted: true,
    };
    let head: Arc<dyn SweepCostHead> = Arc::new(ZnccMean(spec.layout(4), spec));
    let learned = stereo
        .clone()
        .with_learned_cost(Some(LearnedCost::Sweep(head)));
    let (swept, _) = learned.cost_volume(&frame.images, None).unwrap();
    assert_eq!(zncc.data.len(), swept.data.len());
    let worst = zncc
        .data
        .iter()
        .zip(&swept.data)
        .map(|(&a, &b)| (i32::from(a) - i32::from(b)).abs())
        .max()
        .unwrap();
    // Sums in another order: at most a few 1/512 units apart.
    assert!(worst <= 3, "largest difference {worst} units");
    let varied = zncc.data.iter().filter(|&&c| c != zncc.data[0]).count();
    assert!(
        varied > zncc.data.len() / 2,
        "the scene must give varied costs"
    );
}

#[test]
fn a_learned_head_names_the_method_and_every_other_sphere_fills_the_odd_ones() {
    let rig = published_rig(0.25);
    let grid = EquirectGrid::new(24, 96, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(8, 1.0).unwrap();
    let frame = Rendered::new(&room(&rig, 12), &rig);
    let dense = |inputs: usize, outputs: usize, v: f32| omnimvs_stereo::sweepnet::Dense {
        inputs,
        outputs,
        weight: vec![v; inputs * outputs],
        bias: vec![0.0; outputs],
    };
    let spec = FeatureSpec {
        radii: vec![4],
        shifted: false,
    };
    let mlp = Mlp::new(
        "SweepNet+SGM",
        spec.clone(),
        vec![dense(26, 4, 0.1), dense(4, 1, -0.5)],
    )
    .unwrap();
    let params = SgmParams {
        sweep: SweepStep::EveryOther,
        ..SgmParams::default()
    };
    let stereo = SphericalStereo::new(&rig, grid, hyps, params)
        .unwrap()
        .with_learned_cost(Some(LearnedCost::Sweep(Arc::new(mlp))));
    assert_eq!(stereo.learned_cost().unwrap().method_name(), "SweepNet+SGM");
    let (v, _) = stereo.cost_volume(&frame.images, None).unwrap();
    for px in v.data.chunks_exact(8) {
        for n in (1..7).step_by(2) {
            let mean = (u32::from(px[n - 1]) + u32::from(px[n + 1])).div_ceil(2);
            assert_eq!(u32::from(px[n]), mean);
        }
        assert_eq!(px[7], px[6]);
    }
    // A head for another rig size is refused.
    let wrong = Mlp::new("wrong", spec, vec![dense(20, 1, 0.1)]).unwrap();
    let bad = stereo.with_learned_cost(Some(LearnedCost::Sweep(Arc::new(wrong))));
    let err = bad.cost_volume(&frame.images, None).unwrap_err();
    assert!(err.to_string().contains("26"), "{err}");
}

#[test]
fn the_zncc_weight_mixes_the_plain_zncc_cost_into_the_learned_one() {
    let rig = published_rig(0.25);
    let grid = EquirectGrid::new(24, 96, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(8, 1.0).unwrap();
    let frame = Rendered::new(&room(&rig, 13), &rig);
    let stereo = SphericalStereo::new(&rig, grid, hyps, SgmParams::default()).unwrap();
    let (zncc, _) = stereo.cost_volume(&frame.images, None).unwrap();
    let spec = FeatureSpec {
        radii: vec![4],
        shifted: false,
    };
    // All weights zero: the head answers sigmoid(0) = 0.5 everywhere.
    let flat = Mlp::new(
        "flat",
        spec,
        vec![omnimvs_stereo::sweepnet::Dense {
            inputs: 26,
            outputs: 1,
            weight: vec![0.0; 26],
            bias: vec![0.0],
        }],
    )
    .unwrap();
    assert!(flat.clone().with_zncc_weight(1.5).is_err());
    assert!(flat.clone().with_zncc_weight(-0.1).is_err());
    let volume = |weight: f32| {
        let head = flat.clone().with_zncc_weight(weight).unwrap();
        let learned = stereo
            .clone()
            .with_learned_cost(Some(LearnedCost::Sweep(Arc::new(head))));
        learned.cost_volume(&frame.images, None).unwrap().0
    };
    let (alone, zncc_only, half) = (volume(0.0), volume(1.0), volume(0.5));
    let worst = |expected: &dyn Fn(usize) -> f32, got: &[u16]| {
        got.iter()
            .enumerate()
            .map(|(i, &c)| (expected(i) - f32::from(c)).abs())
            .fold(0f32, f32::max)
    };
    // Where no pair sees the point every volume holds the no-pair cost, 0.5 as well.
    assert!(alone.data.iter().all(|&c| c == 256));
    assert!(worst(&|i| f32::from(zncc.data[i]), &zncc_only.data) <= 3.0);
    let mixed = |i: usize| 0.5 * 256.0 + 0.5 * f32::from(zncc.data[i]);
    assert!(worst(&mixed, &half.data) <= 3.0);
    assert!(
        zncc.data.iter().any(|&c| c < 200),
        "the scene must match somewhere"
    );
}
