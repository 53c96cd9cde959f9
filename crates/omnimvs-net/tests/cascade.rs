//! The cascade network: per-pixel sampling equals the lookup table on the spheres they share,
//! every stage has the expected shape, folding the batch norms keeps its answers, the host correlation equals the tensor one, a window of longitudes answers as the whole panorama,
//! the refinement stages follow the centres a caller gives them (another method's answer),
//! and its weight files round-trip (training it: `omnimvs-train`'s `tests/cascade.rs`). Uses the published rig of `sunny_single` from
//! `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use burn::module::Module;
use burn::tensor::Device;
use omnimvs_camera::Rig;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::{CascadeGeometry, ColumnWindow, PixelSampler, SeedChoice};
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig, weights};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{max_difference, micro_config, micro_images};

fn sunny_rig() -> (Rig, InvDepthHypotheses) {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    (ds.rig, hyps)
}

/// The micro images as `[1, 1, H_I, W_I]` tensors on `device`.
fn micro_tensors(config: &NetConfig, device: &Device) -> Vec<burn::tensor::Tensor<4>> {
    micro_images(config)
        .into_iter()
        .map(|img| {
            burn::tensor::Tensor::<4>::from_data(
                burn::tensor::TensorData::new(img, [1, 1, config.input_height, config.input_width]),
                device,
            )
        })
        .collect()
}

/// A micro cascade with random weights on the published rig, its geometry and the micro images.
fn micro_net() -> (
    NetConfig,
    CascadeNet,
    CascadeGeometry,
    Vec<burn::tensor::Tensor<4>>,
) {
    let (rig, hyps) = sunny_rig();
    let config = micro_config();
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let geometry = CascadeGeometry::new(&rig, &config, &hyps, &device).unwrap();
    let images = micro_tensors(&config, &device);
    (config, net, geometry, images)
}

#[test]
fn per_pixel_positions_equal_the_lookup_table_on_its_spheres() {
    let (rig, hyps) = sunny_rig();
    let grid = EquirectGrid::new(16, 64, 45.0).unwrap();
    let table = LookupTable::build(&rig, &grid, &hyps, SphereSet::EveryOther).unwrap();
    let sampler = PixelSampler::new(&rig, &grid, &hyps).unwrap();
    let spheres: Vec<f64> = table.sphere_indices.iter().map(|&n| n as f64).collect();
    let grids = sampler.sphere_grids(&spheres).unwrap();
    let mut compared = 0;
    for (cam, g) in grids.iter().enumerate() {
        let expected = table.camera(cam);
        assert_eq!(g.coords.len(), expected.len());
        for (a, b) in g.coords.iter().zip(expected) {
            if b.abs() > 10.0 {
                // The invalid marker (-1e5 px normalised): ours must be invalid too.
                assert!(a.abs() > 10.0, "valid {a} where the table is invalid");
            } else {
                assert!((a - b).abs() < 1e-5, "{a} vs {b}");
                compared += 1;
            }
        }
    }
    assert!(compared > 10_000, "only {compared} valid entries compared");

    // Per-pixel hypotheses: each pixel at its own sphere gives that sphere's entry.
    let plane = grid.len();
    let index: Vec<f32> = (0..plane).map(|i| (2 * (i % 16)) as f32).collect();
    let per_pixel = sampler.grids(&index, 1).unwrap();
    for i in (0..plane).step_by(37) {
        let sphere = i % 16;
        let want = &table.plane(0, sphere)[2 * i..2 * i + 2];
        let got = &per_pixel[0].coords[2 * i..2 * i + 2];
        if want[0].abs() < 10.0 && want[1].abs() < 10.0 {
            assert!((got[0] - want[0]).abs() < 1e-5 && (got[1] - want[1]).abs() < 1e-5);
        }
    }
    assert!(sampler.grids(&index, 2).is_err());
}

#[test]
fn stages_have_the_expected_shapes_and_stay_in_range() {
    let (config, net, geometry, learner_images) = micro_net();
    let out = net.forward(&learner_images, &geometry).unwrap();
    let sizes = config.cascade_sizes();
    let ks = [
        config.cascade.coarse_spheres,
        config.cascade.stage_hypotheses[0],
        config.cascade.stage_hypotheses[1],
    ];
    for ((stage, [h, w]), k) in out.stages.iter().zip(sizes).zip(ks) {
        assert_eq!(stage.prob.dims(), [1, k, h, w]);
        assert_eq!(stage.index.dims(), [1, h, w]);
        let index = read_values(stage.index.clone(), "index").unwrap();
        assert!(index.iter().all(|&n| (0.0..=31.0 + 1e-3).contains(&n)));
        let sums = read_values(stage.prob.clone().sum_dim(1), "sums").unwrap();
        assert!(sums.iter().all(|s| (s - 1.0).abs() < 1e-4));
    }
    // A batch of two is refused (per-pixel hypotheses are built per frame).
    let two: Vec<_> = learner_images
        .iter()
        .map(|t| burn::tensor::Tensor::cat(vec![t.clone(), t.clone()], 0))
        .collect();
    assert!(net.forward(&two, &geometry).is_err());
    assert!(net.forward(&learner_images[..3], &geometry).is_err());
}

/// Gives a batch norm inference statistics and an affine part away from the identity, from
/// `seed` (channel `c` of seed `s`: mean, variance, scale and shift all differ).
fn perturb(bn: &mut burn::nn::BatchNorm, seed: usize) {
    use burn::module::{Param, RunningState};
    use burn::tensor::{Tensor, TensorData};
    let device = bn.gamma.val().device();
    let n = bn.gamma.val().dims()[0];
    let values = |f: &dyn Fn(f32) -> f32| {
        let v: Vec<f32> = (0..n).map(|c| f((c + 3 * seed) as f32)).collect();
        Tensor::<1>::from_data(TensorData::new(v, [n]), &device)
    };
    bn.gamma = Param::from_tensor(values(&|x| 0.6 + 0.4 * (0.7 * x).sin().abs()));
    bn.beta = Param::from_tensor(values(&|x| 0.2 * (1.3 * x).cos()));
    bn.running_mean = RunningState::new(values(&|x| 0.3 * (0.9 * x).sin()));
    bn.running_var = RunningState::new(values(&|x| 0.5 + (0.4 * x).cos().abs()));
}

#[test]
fn folding_the_batch_norms_keeps_every_stage_answer() {
    let (rig, hyps) = sunny_rig();
    let config = micro_config();
    let device = Device::flex();
    let mut net = CascadeNet::new(&config, &device).unwrap();
    let mut seed = 0;
    let mut next = || {
        seed += 1;
        seed
    };
    let f = &mut net.features;
    for block in [&mut f.conv0, &mut f.conv2, &mut f.down4, &mut f.down8]
        .into_iter()
        .chain(f.res4.iter_mut())
        .chain(f.res8.iter_mut())
        .chain(f.ctx8.iter_mut())
    {
        perturb(block.bn.as_mut().unwrap(), next());
    }
    let c = &mut net.coarse;
    for block in
        c.c0.iter_mut()
            .chain(c.c1.iter_mut())
            .chain(c.c2.iter_mut())
    {
        perturb(block.bn.as_mut().unwrap(), next());
    }
    perturb(&mut c.up1.bn, next());
    perturb(&mut c.up0.bn, next());
    for block in net.mid.convs.iter_mut().chain(net.fine.convs.iter_mut()) {
        perturb(block.bn.as_mut().unwrap(), next());
    }
    let geometry = CascadeGeometry::new(&rig, &config, &hyps, &device).unwrap();
    let images = micro_tensors(&config, &device);
    let plain = net.forward(&images, &geometry).unwrap();
    let folded_net = net.clone().fold_batch_norm();
    assert!(folded_net.features.conv0.bn.is_none() && folded_net.fine.convs[0].bn.is_none());
    let folded = folded_net.forward(&images, &geometry).unwrap();
    for (a, b) in plain.stages.iter().zip(&folded.stages) {
        let a = read_values(a.prob.clone(), "plain").unwrap();
        let b = read_values(b.prob.clone(), "folded").unwrap();
        let max = max_difference(&a, &b);
        assert!(max < 1e-4, "probabilities differ by {max}");
        // The perturbation reaches the answer: the distributions are not uniform.
        let spread = a.iter().fold(0f32, |m, &x| m.max(x)) - a.iter().fold(1f32, |m, &x| m.min(x));
        assert!(spread > 1e-3, "flat distributions");
    }
}

#[test]
fn the_host_correlation_answers_as_the_tensor_one() {
    let (rig, hyps) = sunny_rig();
    let config = micro_config();
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let images = micro_tensors(&config, &device);
    let tensors = CascadeGeometry::new(&rig, &config, &hyps, &device).unwrap();
    let host = CascadeGeometry::with_host_correlation(&rig, &config, &hyps, &device, true).unwrap();
    assert!(host.coarse.host.is_some() && host.coarse.cameras.is_empty());
    let a = net.forward(&images, &tensors).unwrap();
    let b = net.forward(&images, &host).unwrap();
    for (stage, (x, y)) in a.stages.iter().zip(&b.stages).enumerate() {
        let x = read_values(x.prob.clone(), "tensor").unwrap();
        let y = read_values(y.prob.clone(), "host").unwrap();
        let max = max_difference(&x, &y);
        assert!(max < 1e-5, "stage {stage}: probabilities differ by {max}");
    }
    // The volumes themselves, on the coarse stage's taps.
    let features: Vec<_> = images
        .iter()
        .map(|i| net.features.forward(i.clone())[2].clone())
        .collect();
    let groups = config.cascade.groups[2];
    let x = read_values(
        CascadeNet::correlation(&features, &tensors.coarse, groups).unwrap(),
        "tensor",
    )
    .unwrap();
    let y = read_values(
        CascadeNet::correlation(&features, &host.coarse, groups).unwrap(),
        "host",
    )
    .unwrap();
    let scale = x.iter().fold(0f32, |m, v| m.max(v.abs()));
    let max = max_difference(&x, &y);
    assert!(
        scale > 1e-3 && max <= 1e-5 * scale,
        "volumes differ by {max} (scale {scale})"
    );
    // A wrong number of feature maps is refused.
    assert!(CascadeNet::correlation(&features[..3], &host.coarse, groups).is_err());
}

#[test]
fn the_refinement_stages_follow_the_centres_they_are_given() {
    let (rig, hyps) = sunny_rig();
    for gates in [false, true] {
        let mut config = micro_config();
        config.cascade.stage_gates = gates;
        let device = Device::flex();
        let net = CascadeNet::new(&config, &device).unwrap();
        let geometry = CascadeGeometry::new(&rig, &config, &hyps, &device).unwrap();
        let images = micro_tensors(&config, &device);
        let plain = net.forward(&images, &geometry).unwrap();
        let fine_of = |out: &omnimvs_net::cascade::CascadeOutput| {
            read_values(out.stages[2].index.clone(), "fine").unwrap()
        };
        let own = read_values(plain.stages[0].index.clone(), "coarse").unwrap();
        // Its own coarse answer as the centres: the plain forward pass.
        let same = net
            .forward_with_centres(&images, &geometry, |c| Ok(c.to_vec()))
            .unwrap();
        assert_eq!(max_difference(&fine_of(&plain), &fine_of(&same)), 0.0);
        // Centres at index 20 everywhere: the half-resolution hypotheses bracket 20 only
        // (4 hypotheses 2 apart: 17..23), whatever the coarse stage said.
        let moved = net
            .forward_with_centres(&images, &geometry, |c| Ok(vec![20.0; c.len()]))
            .unwrap();
        let mid = read_values(moved.stages[1].hypotheses.clone(), "hypotheses").unwrap();
        assert!(mid.iter().all(|&n| (17.0..=23.0).contains(&n)), "{mid:?}");
        assert!(
            net.forward_with_centres(&images, &geometry, |c| Ok(vec![20.0; c.len() - 1]))
                .is_err()
        );
        // Seeded with its own coarse answer, both runs of the half stage are one: every
        // choice between them answers as the plain pass (the joint soft argmax leaves the
        // gates out, so only without them).
        for choice in [SeedChoice::Peak, SeedChoice::Mass, SeedChoice::Joint] {
            let seeded = net
                .forward_seeded(&images, &geometry, &own, choice)
                .unwrap();
            let d = max_difference(&fine_of(&plain), &fine_of(&seeded));
            if choice != SeedChoice::Joint || !gates {
                assert!(d < 1e-4, "{choice:?}, gates {gates}: {d}");
            }
        }
        // A seed elsewhere: the joint soft argmax is over both runs' hypotheses.
        let joint = net
            .forward_seeded(
                &images,
                &geometry,
                &vec![20.0; own.len()],
                SeedChoice::Joint,
            )
            .unwrap();
        let k = config.cascade.stage_hypotheses[0];
        assert_eq!(joint.stages[1].hypotheses.dims()[1], 2 * k);
        assert!(
            net.forward_seeded(&images, &geometry, &own[1..], SeedChoice::Peak)
                .is_err()
        );
    }
}

#[test]
fn a_window_of_longitudes_gives_the_same_answer_inside_it() {
    // The refinement stages on a window see the same centres as on the whole panorama (the
    // coarse stage always runs whole), so inside the window, away from its edges (where the
    // convolutions wrap around the window instead of the panorama), the index agrees.
    let (config, net, geometry, images) = micro_net();
    let whole = net.forward(&images, &geometry).unwrap();
    let window = ColumnWindow {
        start: 20,
        width: 24,
    };
    let (part, _) = net
        .forward_window(&images, &geometry, Some(window), false, false)
        .unwrap();
    let [_, _, fine] = config.cascade_sizes();
    assert_eq!(part.stages[2].index.dims(), [1, fine[0], 24]);
    assert_eq!(part.stages[1].index.dims(), [1, fine[0] / 2, 12]);
    let full = read_values(whole.stages[2].index.clone(), "whole").unwrap();
    let cut = read_values(part.stages[2].index.clone(), "window").unwrap();
    // Columns 4..20 of the window: three 3x3 layers per stage, two stages, stay inside.
    for row in 0..fine[0] {
        for c in 8..16 {
            let a = full[row * fine[1] + window.start + c];
            let b = cut[row * 24 + c];
            assert!((a - b).abs() < 1e-3, "row {row} col {c}: {a} vs {b}");
        }
    }
    let odd = ColumnWindow { start: 3, width: 8 };
    assert!(
        net.forward_window(&images, &geometry, Some(odd), false, false)
            .is_err()
    );
    let outside = ColumnWindow {
        start: 60,
        width: 8,
    };
    assert!(
        net.forward_window(&images, &geometry, Some(outside), false, false)
            .is_err()
    );
}

#[test]
fn weights_round_trip_and_the_family_is_recorded() {
    let config = micro_config();
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cascade.safetensors");
    weights::save_module(&net, &net.config, &path).unwrap();
    let json = std::fs::read_to_string(weights::config_path(&path)).unwrap();
    assert!(json.contains("\"cascade\""), "{json}");
    let back = weights::load_cascade(&path, &device).unwrap();
    assert_eq!(back.config, config);
    assert_eq!(back.num_params(), net.num_params());
    // The paper's loader refuses it with a message that names the family.
    let err = weights::load(&path, &device).unwrap_err().to_string();
    assert!(err.contains("family"), "{err}");
    match weights::load_family(&path, &NetConfig::tiny(), &device).unwrap() {
        weights::AnyNet::Cascade(n) => assert_eq!(n.config, config),
        weights::AnyNet::OmniMvs(_) => panic!("loaded as the paper's network"),
    }
}
