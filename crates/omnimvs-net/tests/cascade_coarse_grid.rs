//! The coarse stage on the half-resolution grid (`coarse_scale` 2): the setting is checked
//! and written only when it is not the default, a network with it runs every stage at the
//! expected sizes and learns, and a trained network moves to it (and to other spheres) with
//! its first convolution keeping its output for evidence linear over inverse depth and its
//! scores interpolated at the new spheres. Uses the published rig of `sunny_single` from
//! `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use burn::optim::GradientsParams;
use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig, NetError, weights};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{max_difference, micro_config, micro_image_tensors as images};

fn half_grid(config: &NetConfig) -> NetConfig {
    let mut moved = config.clone();
    moved.cascade.coarse_scale = 2;
    moved
}

fn invalid_field(config: &NetConfig) -> &'static str {
    match config.validate() {
        Err(NetError::InvalidConfig { field, .. }) => field,
        other => panic!("expected an invalid configuration, got {other:?}"),
    }
}

/// A tensor of `dims` with values from a fixed pseudo-random sequence (`seed`).
fn noise(dims: [usize; 4], seed: u32, device: &Device) -> Tensor<4> {
    let n: usize = dims.iter().product();
    let values: Vec<f32> = (0..n)
        .map(|i| ((i as f32 * 0.618 + seed as f32 * 1.37).sin() * 43758.547).fract() - 0.5)
        .collect();
    Tensor::from_data(TensorData::new(values, dims), device)
}

#[test]
fn the_coarse_scale_is_checked_and_written_only_off_its_default() {
    let paper = NetConfig::cascade();
    assert_eq!(paper.cascade.coarse_scale, 4);
    assert!(
        !serde_json::to_string(&paper)
            .unwrap()
            .contains("coarse_scale")
    );
    let moved = half_grid(&paper);
    moved.validate().unwrap();
    assert_eq!(
        moved.cascade_sizes(),
        [[80, 320], [80, 320], [160, 640]],
        "the coarse stage shares the half-resolution grid"
    );
    let json = serde_json::to_string(&moved).unwrap();
    assert!(json.contains("\"coarse_scale\":2"));
    assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), moved);

    let mut odd = paper.clone();
    odd.cascade.coarse_scale = 3;
    assert_eq!(invalid_field(&odd), "cascade.coarse_scale");
    // On the half grid the cue is matched on the coarse grid itself.
    let mut cued = moved.clone();
    cued.cascade.zncc_cue = true;
    cued.cascade.coarse_cue_oversample = 2;
    assert_eq!(invalid_field(&cued), "cascade.coarse_scale");
    cued.cascade.coarse_cue_oversample = 1;
    cued.validate().unwrap();
}

#[test]
fn a_cascade_with_its_coarse_stage_on_the_half_grid_runs_and_learns() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let mut config = half_grid(&micro_config());
    config.cascade.convex_upsampling = true;
    config.cascade.zncc_cue = true;
    config.cascade.coarse_cue_sgm = true;
    config.cascade.coarse_cue_depths = 3;
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    assert!(net.up_mid.is_none(), "nothing to upsample to the half grid");
    assert!(net.up_fine.is_some());
    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    // The cue on the coarse grid: one plane per sphere and depth of its 8 x 32 pixels.
    let grid = &geometry.coarse_grids[0];
    assert_eq!([grid.height, grid.width], [8, 32]);
    assert_eq!(grid.num_spheres, 3 * config.cascade.coarse_spheres);

    let out = net.forward(&images(&config, &device), &geometry).unwrap();
    let ks = [
        config.cascade.coarse_spheres,
        config.cascade.stage_hypotheses[0],
        config.cascade.stage_hypotheses[1],
    ];
    for (s, ([h, w], k)) in [[8, 32], [8, 32], [16, 64]].into_iter().zip(ks).enumerate() {
        assert_eq!(out.stages[s].prob.dims(), [1, k, h, w], "stage {s}");
        let index = read_values(out.stages[s].index.clone(), "index").unwrap();
        assert!(index.iter().all(|&n| (0.0..=31.0 + 1e-3).contains(&n)));
    }
    assert!(out.upsampled[0].is_none());

    // The half stage centres on the coarse answer itself: every hypothesis window holds it.
    let coarse = read_values(out.stages[0].index.clone(), "coarse").unwrap();
    let hyp = read_values(out.stages[1].hypotheses.clone(), "hypotheses").unwrap();
    let plane = coarse.len();
    let spread = config.cascade.stage_intervals[0] as f32 * (ks[1] - 1) as f32;
    for (p, &c) in coarse.iter().enumerate() {
        let (lo, hi) = (0..ks[1])
            .map(|j| hyp[j * plane + p])
            .fold((f32::MAX, f32::MIN), |(a, b), v| (a.min(v), b.max(v)));
        assert!(
            lo <= c + 1e-3 && c - 1e-3 <= hi,
            "pixel {p}: {c} outside {lo}..{hi}"
        );
        assert!(hi - lo <= spread + 1e-3);
    }

    // Gradients reach the coarse stage's first and scoring convolutions.
    let device = Device::flex().autodiff();
    let net = CascadeNet::new(&config, &device).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let out = net.forward(&images(&config, &device), &geometry).unwrap();
    let loss = out
        .stages
        .into_iter()
        .map(|s| s.index.sub_scalar(10.0).abs().mean())
        .reduce(|a, b| a + b)
        .unwrap();
    let grads = GradientsParams::from_grads(loss.backward(), &net);
    for (name, id) in [
        ("coarse first", net.coarse.c0[0].conv.weight.id),
        ("coarse scores", net.coarse.out.conv.weight.id),
    ] {
        let grad = grads.get::<4>(id).unwrap_or_else(|| panic!("{name}: none"));
        let norm: f32 = read_values(grad, name)
            .unwrap()
            .iter()
            .map(|g| g.abs())
            .sum();
        assert!(norm > 0.0 && norm.is_finite(), "{name}: {norm}");
    }
}

#[test]
fn a_moved_coarse_stage_keeps_linear_evidence_and_interpolates_its_scores() {
    let config = micro_config(); // N = 32, 8 spheres, groups 4 at stride 8
    let device = Device::flex();
    let old = CascadeNet::new(&config, &device).unwrap();
    let (k_old, k_new, n) = (8usize, 5usize, 32usize);
    let moved = old.clone().with_coarse_grid(2, k_new).unwrap();
    assert_eq!(moved.config.cascade.coarse_scale, 2);
    assert_eq!(moved.config.cascade.coarse_spheres, k_new);
    let channels = config.cascade.groups[2] + 1;
    assert_eq!(moved.coarse.c0[0].conv.weight.dims()[1], channels * k_new);
    assert_eq!(moved.coarse.out.conv.weight.dims()[0], k_new);
    // Everything else is kept.
    let same = |a: Tensor<4>, b: Tensor<4>| {
        max_difference(&read_values(a, "a").unwrap(), &read_values(b, "b").unwrap())
    };
    assert_eq!(
        same(
            old.coarse.c1[0].conv.weight.val(),
            moved.coarse.c1[0].conv.weight.val()
        ),
        0.0
    );

    // Evidence linear in the sphere's inverse-depth index, per channel and pixel.
    let (h, w) = (4, 8);
    let position = |k: usize, i: usize| i as f32 * (n - 1) as f32 / (k - 1) as f32;
    let slope = noise([1, channels, h, w], 1, &device);
    let offset = noise([1, channels, h, w], 2, &device);
    let volume = |k: usize| {
        let planes: Vec<Tensor<4>> = (0..channels)
            .flat_map(|c| {
                let (s, o) = (
                    slope.clone().narrow(1, c, 1),
                    offset.clone().narrow(1, c, 1),
                );
                (0..k).map(move |i| s.clone().mul_scalar(position(k, i) / 31.0) + o.clone())
            })
            .collect();
        Tensor::cat(planes, 1) // [1, channels x k, h, w], the sphere fastest
    };
    let before = old.coarse.c0[0].forward(volume(k_old), None);
    let after = moved.coarse.c0[0].forward(volume(k_new), None);
    let diff = same(before, after);
    assert!(diff < 1e-4, "first convolution moved by {diff}");

    // The new scores are the old ones interpolated at the new spheres' inverse depths.
    let hidden = noise([1, config.cascade.coarse_channels[0], h, w], 3, &device);
    let old_scores = read_values(old.coarse.out.forward(hidden.clone(), None), "old").unwrap();
    let new_scores = read_values(moved.coarse.out.forward(hidden, None), "new").unwrap();
    let plane = h * w;
    for j in 0..k_new {
        let u = position(k_new, j) * (k_old - 1) as f32 / (n - 1) as f32;
        let (i0, f) = (u.floor() as usize, u - u.floor());
        let i1 = (i0 + 1).min(k_old - 1);
        for p in 0..plane {
            let want = old_scores[i0 * plane + p] * (1.0 - f) + old_scores[i1 * plane + p] * f;
            let got = new_scores[j * plane + p];
            assert!(
                (got - want).abs() < 1e-4,
                "sphere {j} pixel {p}: {got} vs {want}"
            );
        }
    }

    // Moving to the same grid and spheres changes nothing.
    let kept = old.clone().with_coarse_grid(4, k_old).unwrap();
    assert_eq!(
        same(
            old.coarse.c0[0].conv.weight.val(),
            kept.coarse.c0[0].conv.weight.val()
        ),
        0.0
    );
    // An invalid move is refused.
    assert!(old.with_coarse_grid(3, k_new).is_err());
}

#[test]
fn saved_weights_move_to_the_half_grid_when_loaded_and_not_back() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let mut config = micro_config();
    config.cascade.convex_upsampling = true;
    config.cascade.zncc_cue = true;
    config.cascade.coarse_cue_oversample = 2;
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("quarter.safetensors");
    weights::save_module(&net, &config, &path).unwrap();

    let mut moved_config = half_grid(&config);
    moved_config.cascade.coarse_spheres = 6;
    moved_config.cascade.coarse_cue_oversample = 1;
    let moved = weights::load_cascade_grown(&path, &moved_config, &device).unwrap();
    assert_eq!(moved.config, moved_config);
    assert!(moved.up_mid.is_none());
    // Groups, visibility and cue per sphere.
    let inputs = (config.cascade.groups[2] + 2) * 6;
    assert_eq!(moved.coarse.c0[0].conv.weight.dims()[1], inputs);
    let geometry = CascadeGeometry::new(&ds.rig, &moved_config, &hyps, &device).unwrap();
    let out = moved
        .forward(&images(&moved_config, &device), &geometry)
        .unwrap();
    assert_eq!(out.stages[0].index.dims(), [1, 8, 32]);
    // The refinement stages' weights are the file's.
    let a = read_values(net.fine.convs[0].conv.weight.val(), "a").unwrap();
    let b = read_values(moved.fine.convs[0].conv.weight.val(), "b").unwrap();
    assert_eq!(max_difference(&a, &b), 0.0);

    // On the same grid the cue's grid may change too (no weight depends on it), and the
    // loaded network answers with the one asked for.
    let mut own_grid = config.clone();
    own_grid.cascade.coarse_cue_oversample = 1;
    let reread = weights::load_cascade_grown(&path, &own_grid, &device).unwrap();
    assert_eq!(reread.config, own_grid);

    // A file on the half grid does not load into a quarter-grid network.
    let moved_path = dir.path().join("half.safetensors");
    weights::save_module(&moved, &moved_config, &moved_path).unwrap();
    assert!(weights::load_cascade_grown(&moved_path, &config, &device).is_err());
    let again = weights::load_cascade_grown(&moved_path, &moved_config, &device).unwrap();
    assert_eq!(again.config, moved_config);
}

#[test]
fn the_stride4_correlation_grows_in_unchanged_and_learns() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let mut config = half_grid(&micro_config());
    config.cascade.zncc_cue = true;
    config.cascade.coarse_cue_sgm = true;
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("stride8.safetensors");
    weights::save_module(&net, &config, &path).unwrap();

    let mut sharp = config.clone();
    sharp.cascade.coarse_stride4 = true;
    let grown = weights::load_cascade_grown(&path, &sharp, &device).unwrap();
    let (k, [g4, g8]) = (
        config.cascade.coarse_spheres,
        [config.cascade.groups[1], config.cascade.groups[2]],
    );
    // Stride-8 groups, visibility, cue, aggregated cue, then the stride-4 groups.
    assert_eq!(grown.coarse.c0[0].conv.weight.dims()[1], (g8 + 3 + g4) * k);
    let inputs = images(&config, &device);
    let before = net
        .forward(
            &inputs,
            &CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap(),
        )
        .unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &sharp, &hyps, &device).unwrap();
    assert!(geometry.coarse4.is_some());
    let after = grown.forward(&inputs, &geometry).unwrap();
    for s in 0..3 {
        let a = read_values(before.stages[s].index.clone(), "before").unwrap();
        let b = read_values(after.stages[s].index.clone(), "after").unwrap();
        assert!(max_difference(&a, &b) < 1e-4, "stage {s}");
    }
    // The network without it does not run on a geometry with it, nor the other way.
    assert!(net.forward(&inputs, &geometry).is_err());

    // The new inputs learn.
    let device = Device::flex().autodiff();
    let net = CascadeNet::new(&config, &device)
        .unwrap()
        .with_coarse_stride4()
        .unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &sharp, &hyps, &device).unwrap();
    let out = net.forward(&images(&sharp, &device), &geometry).unwrap();
    let loss = out.stages[0].index.clone().sub_scalar(10.0).abs().mean();
    let grads = GradientsParams::from_grads(loss.backward(), &net);
    let grad = grads
        .get::<4>(net.coarse.c0[0].conv.weight.id)
        .unwrap()
        .narrow(1, (g8 + 3) * k, g4 * k);
    let norm: f32 = read_values(grad, "grad")
        .unwrap()
        .iter()
        .map(|g| g.abs())
        .sum();
    assert!(norm > 0.0 && norm.is_finite(), "{norm}");

    // A cue switched on later goes before the stride-4 inputs, which keep their weights.
    let device = Device::flex();
    let mut plain = micro_config();
    plain.cascade.coarse_stride4 = true;
    let net = CascadeNet::new(&plain, &device).unwrap();
    let tail = |net: &CascadeNet| {
        let w = net.coarse.c0[0].conv.weight.val();
        let c_in = w.dims()[1];
        read_values(w.narrow(1, c_in - g4 * k, g4 * k), "tail").unwrap()
    };
    let old_tail = tail(&net);
    let cued = net.with_zncc_cue().with_coarse_cue_sgm().unwrap();
    assert_eq!(cued.coarse.c0[0].conv.weight.dims()[1], (g8 + 3 + g4) * k);
    assert_eq!(max_difference(&old_tail, &tail(&cued)), 0.0);
}
