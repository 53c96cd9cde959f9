//! A trained cascade grows into context pairs at stride 8, gated refinement stages and the
//! photometric cue without changing its answer (the gates start at 0.98: within 2 % of each refinement's
//! step), a file of the grown network does not load into the smaller one, and the new
//! modules receive gradients. Uses the published rig of `sunny_single` from
//! `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use burn::nn::conv::Conv2d;
use burn::optim::GradientsParams;
use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::photo::ImagePyramid;
use omnimvs_net::cascade::{CascadeGeometry, CascadeOutput};
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig, weights};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{micro_config, micro_image_tensors as images};

fn grown(config: &NetConfig) -> NetConfig {
    let mut big = config.clone();
    big.cascade.context_pairs = 2;
    big.cascade.stage_gates = true;
    big
}

/// The input channels of the first convolution of the coarse, half- and full-resolution stages.
fn first_inputs(net: &CascadeNet) -> [usize; 3] {
    [
        net.coarse.c0[0].conv.weight.dims()[1],
        net.mid.convs[0].conv.weight.dims()[1],
        net.fine.convs[0].conv.weight.dims()[1],
    ]
}

/// Asserts that two forward passes give every stage the same index map (within 1e-4).
fn assert_same_answers(before: &CascadeOutput, after: &CascadeOutput) {
    for s in 0..3 {
        let a = read_values(before.stages[s].index.clone(), "index").unwrap();
        let b = read_values(after.stages[s].index.clone(), "index").unwrap();
        let diff = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        assert!(diff < 1e-4, "stage {s} moved by {diff}");
    }
}

/// Asserts that the last `k` input channels of the convolution `conv` (`name` in messages)
/// get a finite, non-zero gradient.
fn assert_new_inputs_learn(grads: &GradientsParams, conv: &Conv2d, k: usize, name: &str) {
    let [c_out, c_in, kh, kw] = conv.weight.dims();
    let grad = grads
        .get::<4>(conv.weight.id)
        .unwrap_or_else(|| panic!("no gradient for {name}"))
        .narrow(1, c_in - k, k);
    assert_eq!(grad.dims(), [c_out, k, kh, kw]);
    let norm: f32 = read_values(grad, "grad")
        .unwrap()
        .iter()
        .map(|g| g.abs())
        .sum();
    assert!(norm > 0.0 && norm.is_finite(), "{name}: {norm}");
}

/// A loss that pulls every stage's answer towards index 10 (for gradients to check).
fn pull_to_ten(out: omnimvs_net::cascade::CascadeOutput) -> burn::tensor::Tensor<1> {
    out.stages
        .into_iter()
        .map(|s| s.index.sub_scalar(10.0).abs().mean())
        .reduce(|a, b| a + b)
        .unwrap()
}

#[test]
fn a_grown_network_answers_as_the_one_it_grew_from() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let config = micro_config();
    let device = Device::flex();
    let small = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("small.safetensors");
    weights::save_module(&small, &config, &path).unwrap();

    let big_config = grown(&config);
    let big = weights::load_cascade_grown(&path, &big_config, &device).unwrap();
    assert_eq!(big.features.ctx8.len(), 4);
    assert!(big.mid.gate.is_some() && big.fine.gate.is_some());

    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let inputs = images(&config, &device);
    let before = small.forward(&inputs, &geometry).unwrap();
    let after = big.forward(&inputs, &geometry).unwrap();
    let stage = |out: &omnimvs_net::cascade::CascadeOutput, s: usize| {
        read_values(out.stages[s].index.clone(), "index").unwrap()
    };
    // The context pairs start as the identity: the coarse stage is unchanged.
    let max_diff = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max)
    };
    assert!(max_diff(&stage(&before, 0), &stage(&after, 0)) < 1e-4);
    // The half stage's centres are the same; its answer moves 2 % of the way to the centre.
    // Its hypotheses lie within (K - 1) x 2 = 6 index units of the centre (the block of
    // hypotheses shifts at the ends of the range), so the step is at most 0.018 x 6.
    let half_diff = max_diff(&stage(&before, 1), &stage(&after, 1));
    assert!(half_diff <= 0.15, "half stage moved by {half_diff}");
    assert!(half_diff > 0.0, "the gate changed nothing");
    // The file of the grown network does not fit the small one, nor another size.
    let big_path = dir.path().join("big.safetensors");
    weights::save_module(&big, &big_config, &big_path).unwrap();
    assert!(weights::load_cascade_grown(&big_path, &config, &device).is_err());
    let mut other = big_config.clone();
    other.cascade.stage_channels = [8, 4];
    assert!(weights::load_cascade_grown(&path, &other, &device).is_err());
    // The same configuration loads as it was saved.
    let again = weights::load_cascade_grown(&big_path, &big_config, &device).unwrap();
    let again_out = again.forward(&inputs, &geometry).unwrap();
    assert!(max_diff(&stage(&after, 2), &stage(&again_out, 2)) < 1e-5);
}

#[test]
fn the_new_modules_learn() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let config = grown(&micro_config());
    let device = Device::flex().autodiff();
    let net = CascadeNet::new(&config, &device).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let out = net.forward(&images(&config, &device), &geometry).unwrap();
    // The gates and the context pairs get gradients.
    let grads = GradientsParams::from_grads(pull_to_ten(out).backward(), &net);
    let norm = |name: &str, grad: Option<Vec<f32>>| {
        let grad = grad.unwrap_or_else(|| panic!("no gradient for {name}"));
        let norm: f32 = grad.iter().map(|g| g.abs()).sum();
        assert!(norm > 0.0 && norm.is_finite(), "{name}: {norm}");
    };
    let read4 = |id| grads.get::<4>(id).map(|g| read_values(g, "grad").unwrap());
    let read1 = |id| grads.get::<1>(id).map(|g| read_values(g, "grad").unwrap());
    norm(
        "mid.gate",
        read4(net.mid.gate.as_ref().unwrap().conv.weight.id),
    );
    norm(
        "fine.gate",
        read4(net.fine.gate.as_ref().unwrap().conv.weight.id),
    );
    // A residual branch that starts at zero learns through its batch norm's scale first.
    for i in [1, 3] {
        let bn = net.features.ctx8[i].bn.as_ref().unwrap();
        norm(&format!("features.ctx8.{i}.bn.gamma"), read1(bn.gamma.id));
    }
}

#[test]
fn a_network_grows_into_the_photometric_cue_unchanged_and_learns_it() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let config = micro_config();
    let mut cued = config.clone();
    cued.cascade.zncc_cue = true;
    let device = Device::flex();
    let small = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("small.safetensors");
    weights::save_module(&small, &config, &path).unwrap();
    let big = weights::load_cascade_grown(&path, &cued, &device).unwrap();
    assert!(big.config.cascade.zncc_cue);
    // The first convolution of every stage reads one more channel per hypothesis.
    let [c, m, f] = first_inputs(&small);
    assert_eq!(first_inputs(&big), [c + 8, m + 4, f + 3]);

    let inputs = images(&config, &device);
    let plain = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let with_cue = CascadeGeometry::new(&ds.rig, &cued, &hyps, &device).unwrap();
    let before = small.forward(&inputs, &plain).unwrap();
    let after = big.forward(&inputs, &with_cue).unwrap();
    assert_same_answers(&before, &after);
    // The cue is there: ZNCC values, not all zero.
    let pyramid = ImagePyramid::from_inputs(&inputs).unwrap();
    let cue = with_cue.coarse_cue(Some(&pyramid)).unwrap().unwrap();
    assert_eq!(cue.dims(), [1, 1, 8, 4, 16]);
    let cue = read_values(cue, "cue").unwrap();
    assert!(cue.iter().all(|z| (-1.0..=1.0).contains(z)));
    assert!(cue.iter().any(|&z| z.abs() > 0.05), "{cue:?}");
    // A network with the cue needs it, and its file does not load into one without.
    assert!(big.forward(&inputs, &plain).is_err());
    let big_path = dir.path().join("big.safetensors");
    weights::save_module(&big, &cued, &big_path).unwrap();
    assert!(weights::load_cascade_grown(&big_path, &config, &device).is_err());

    // The cue's weights, zero at the start, get gradients.
    let device = Device::flex().autodiff();
    let net = weights::load_cascade_grown(&path, &cued, &device).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &cued, &hyps, &device).unwrap();
    let out = net.forward(&images(&cued, &device), &geometry).unwrap();
    let grads = GradientsParams::from_grads(pull_to_ten(out).backward(), &net);
    let firsts = [
        ("coarse", &net.coarse.c0[0], 8),
        ("mid", &net.mid.convs[0], 4),
        ("fine", &net.fine.convs[0], 3),
    ];
    for (name, conv, k) in firsts {
        assert_new_inputs_learn(&grads, &conv.conv, k, name);
    }
}

#[test]
fn a_network_grows_into_learnt_upsampling_and_only_its_heads_need_to_learn() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let config = micro_config();
    let mut learnt = config.clone();
    learnt.cascade.convex_upsampling = true;
    let device = Device::flex();
    let small = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("small.safetensors");
    weights::save_module(&small, &config, &path).unwrap();
    let big = weights::load_cascade_grown(&path, &learnt, &device).unwrap();
    assert!(big.up_mid.is_some() && big.up_fine.is_some());

    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let inputs = images(&config, &device);
    let before = small.forward(&inputs, &geometry).unwrap();
    let after = big.forward(&inputs, &geometry).unwrap();
    let values = |t: burn::tensor::Tensor<3>| read_values(t, "index").unwrap();
    // The coarse stage is the same; the heads start near the bilinear resampling (a quarter
    // row in latitude, under 5 % of the weight elsewhere), so the half stage's centres move
    // by at most a quarter of the coarse answer's step between neighbouring rows and 5 % of
    // the largest step between neighbours.
    let coarse = values(before.stages[0].index.clone());
    assert_eq!(coarse, values(after.stages[0].index.clone()));
    let [Some(up_mid), Some(up_fine)] = after.upsampled.clone() else {
        panic!("a network with learnt upsampling reports its centres");
    };
    assert_eq!(up_mid.dims(), [1, 8, 32]);
    assert_eq!(up_fine.dims(), [1, 16, 64]);
    let (h, w) = (4, 16);
    let row_step = (0..(h - 1) * w)
        .map(|i| (coarse[i + w] - coarse[i]).abs())
        .fold(0.0f32, f32::max);
    let any_step = (0..h * w)
        .map(|i| (coarse[i] - coarse[(i / w) * w + (i + 1) % w]).abs())
        .fold(row_step, f32::max);
    let bilinear = omnimvs_sweep::resample_map(
        &coarse,
        geometry.samplers[0].grid(),
        geometry.samplers[1].grid(),
    );
    let moved = values(up_mid)
        .iter()
        .zip(&bilinear)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(
        moved <= 0.25 * row_step + 0.05 * 2.0 * any_step + 1e-3,
        "{moved} against steps of {row_step} (rows), {any_step}"
    );
    assert!(before.upsampled.iter().all(Option::is_none));
    // A file with the heads does not load into the network without them.
    let big_path = dir.path().join("big.safetensors");
    weights::save_module(&big, &learnt, &big_path).unwrap();
    assert!(weights::load_cascade_grown(&big_path, &config, &device).is_err());
    let again = weights::load_cascade_grown(&big_path, &learnt, &device).unwrap();
    let again_out = again.forward(&inputs, &geometry).unwrap();
    assert_eq!(
        values(after.stages[2].index.clone()),
        values(again_out.stages[2].index.clone())
    );

    // The heads get gradients from a loss on the centres they make (their last convolution
    // first: it starts with zero weights, so the one before it learns once it has moved).
    let device = Device::flex().autodiff();
    let net = weights::load_cascade_grown(&path, &learnt, &device).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &learnt, &hyps, &device).unwrap();
    let out = net.forward(&images(&learnt, &device), &geometry).unwrap();
    let loss = out
        .upsampled
        .into_iter()
        .flatten()
        .map(|u| u.sub_scalar(10.0).abs().mean())
        .reduce(|a, b| a + b)
        .unwrap();
    let grads = GradientsParams::from_grads(loss.backward(), &net);
    for (name, head) in [("up_mid", &net.up_mid), ("up_fine", &net.up_fine)] {
        let head = head.as_ref().unwrap();
        let weight = grads
            .get::<4>(head.out.weight.id)
            .map(|g| read_values(g, "grad"));
        let bias = head.out.bias.as_ref().and_then(|b| grads.get::<1>(b.id));
        let bias = bias.map(|g| read_values(g, "grad"));
        for grad in [weight, bias] {
            let grad = grad
                .unwrap_or_else(|| panic!("no gradient for {name}"))
                .unwrap();
            let norm: f32 = grad.iter().map(|g| g.abs()).sum();
            assert!(norm > 0.0 && norm.is_finite(), "{name}: {norm}");
        }
    }
}

/// A network with learnt upsampling on both grids loads without the full grid's selector
/// (`convex_upsampling_full` off: its tensors left unused): the half grid's centres are
/// unchanged and the full stage centres on the bilinear upsampling of the half stage, as the
/// plain network's does. The half-grid file grows back into both, the full selector new.
#[test]
fn the_full_grid_selector_can_be_left_out_and_grown_back() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let mut both = micro_config();
    both.cascade.convex_upsampling = true;
    let mut half = both.clone();
    half.cascade.convex_upsampling_full = false;
    let device = Device::flex();
    let net = CascadeNet::new(&both, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let both_path = dir.path().join("both.safetensors");
    weights::save_module(&net, &both, &both_path).unwrap();
    let dropped = weights::load_cascade_grown(&both_path, &half, &device).unwrap();
    assert!(dropped.up_mid.is_some() && dropped.up_fine.is_none());
    assert!(CascadeNet::new(&half, &device).unwrap().up_fine.is_none());

    let geometry = CascadeGeometry::new(&ds.rig, &both, &hyps, &device).unwrap();
    let inputs = images(&both, &device);
    let values = |t: burn::tensor::Tensor<3>| read_values(t, "index").unwrap();
    let full = net.forward(&inputs, &geometry).unwrap();
    let out = dropped.forward(&inputs, &geometry).unwrap();
    let [Some(up_mid), None] = out.upsampled.clone() else {
        panic!("the half grid's centres only");
    };
    let [Some(full_mid), Some(_)] = full.upsampled.clone() else {
        panic!("both grids' centres");
    };
    assert_eq!(values(up_mid), values(full_mid));
    let mid = values(out.stages[1].index.clone());
    assert_eq!(mid, values(full.stages[1].index.clone()));
    // The full stage's centres are the bilinear upsampling of the half stage's answer.
    let fine_taps = geometry.refine_taps(2, &mid, 0..64, None).unwrap();
    let stride2 = dropped
        .features
        .forward(burn::tensor::Tensor::cat(inputs.clone(), 0))[0]
        .clone();
    let stride2: Vec<_> = (0..inputs.len())
        .map(|c| stride2.clone().narrow(0, c, 1))
        .collect();
    let bilinear = dropped.refine_stage(0, &stride2, &fine_taps);
    assert_eq!(
        values(bilinear.unwrap().index),
        values(out.stages[2].index.clone())
    );

    let half_path = dir.path().join("half.safetensors");
    weights::save_module(&dropped, &half, &half_path).unwrap();
    assert!(weights::read_config(&weights::config_path(&half_path)).unwrap() == half);
    let again = weights::load_cascade(&half_path, &device).unwrap();
    assert!(again.up_fine.is_none());
    let grown = weights::load_cascade_grown(&half_path, &both, &device).unwrap();
    assert!(grown.up_fine.is_some());
    // A file without any selector does not lose what it never had.
    assert!(weights::load_cascade_grown(&half_path, &micro_config(), &device).is_err());
}

#[test]
fn weights_load_into_a_network_of_another_refinement_spacing() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let config = micro_config();
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("net.safetensors");
    weights::save_module(&net, &config, &path).unwrap();

    let mut wider = config.clone();
    wider.cascade.stage_intervals = [3.0, 1.5];
    let loaded = weights::load_cascade_grown(&path, &wider, &device).unwrap();
    assert_eq!(loaded.config.cascade.stage_intervals, [3.0, 1.5]);
    // The same weights...
    let weight = |n: &CascadeNet| read_values(n.fine.out.conv.weight.val(), "w").unwrap();
    assert_eq!(weight(&net), weight(&loaded));
    // ...answer with the new spacing: the same coarse stage, the full stage's hypotheses
    // 1.5 apart instead of 1.
    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let wide_geometry = CascadeGeometry::new(&ds.rig, &wider, &hyps, &device).unwrap();
    let inputs = images(&config, &device);
    let before = net.forward(&inputs, &geometry).unwrap();
    let after = loaded.forward(&inputs, &wide_geometry).unwrap();
    let values = |t: burn::tensor::Tensor<4>| read_values(t, "hypotheses").unwrap();
    assert_eq!(
        read_values(before.stages[0].index.clone(), "coarse").unwrap(),
        read_values(after.stages[0].index.clone(), "coarse").unwrap()
    );
    let step = |h: &[f32], plane: usize| h[plane] - h[0];
    let (narrow, wide) = (
        values(before.stages[2].hypotheses.clone()),
        values(after.stages[2].hypotheses.clone()),
    );
    let plane = narrow.len() / config.cascade.stage_hypotheses[1];
    let (a, b) = (step(&narrow, plane), step(&wide, plane));
    assert!(
        (a - 1.0).abs() < 1e-4 && (b - 1.5).abs() < 1e-4,
        "hypothesis spacing {a} and {b}"
    );
}

#[test]
fn the_stride_8_features_widen_keeping_the_coarse_answer_and_the_new_channels_learn() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let config = micro_config(); // stride 8: 8 channels in 4 groups of 2
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("net.safetensors");
    weights::save_module(&net, &config, &path).unwrap();

    let mut wide = config.clone();
    wide.cascade.feature_channels[2] = 16; // 4 groups of 4
    let loaded = weights::load_cascade_grown(&path, &wide, &device).unwrap();
    assert_eq!(loaded.config.cascade.feature_channels, [4, 4, 16]);
    assert_eq!(loaded.features.out8.conv.weight.dims(), [16, 16, 1, 1]);

    // Every old channel is in its group, scaled by sqrt(4 / 2); the other strides are untouched.
    let inputs = images(&config, &device);
    let [f2, _, f8] = net.features.forward(inputs[0].clone());
    let [g2, _, g8] = loaded.features.forward(inputs[0].clone());
    let (f8, g8) = (
        read_values(f8, "f8").unwrap(),
        read_values(g8, "g8").unwrap(),
    );
    assert_eq!(
        read_values(f2, "f2").unwrap(),
        read_values(g2, "g2").unwrap()
    );
    let plane = f8.len() / 8;
    for g in 0..4 {
        for j in 0..2 {
            let (old, new) = (g * 2 + j, g * 4 + j);
            for p in 0..plane {
                let (a, b) = (f8[old * plane + p] * 2f32.sqrt(), g8[new * plane + p]);
                assert!(
                    (a - b).abs() <= 1e-4 * (1.0 + a.abs()),
                    "channel {old} -> {new}: {a} {b}"
                );
            }
        }
    }
    // So the coarse answer moves only by the new channels' small products.
    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let before = net.forward(&inputs, &geometry).unwrap();
    let after = loaded.forward(&inputs, &geometry).unwrap();
    let coarse = |out: &omnimvs_net::cascade::CascadeOutput| {
        read_values(out.stages[0].index.clone(), "coarse").unwrap()
    };
    let moved = coarse(&before)
        .iter()
        .zip(coarse(&after))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(moved < 0.05, "the coarse answer moved by {moved}");
    // Narrowing, or a width the groups do not divide, is refused.
    let wide_path = dir.path().join("wide.safetensors");
    weights::save_module(&loaded, &wide, &wide_path).unwrap();
    assert!(weights::load_cascade_grown(&wide_path, &config, &device).is_err());
    let mut odd = config.clone();
    odd.cascade.feature_channels[2] = 10;
    assert!(weights::load_cascade_grown(&path, &odd, &device).is_err());

    // The new channels get gradients from the coarse stage: the new trunk rows and the
    // projection's new rows.
    let device = Device::flex().autodiff();
    let learner = weights::load_cascade_grown(&path, &wide, &device).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &wide, &hyps, &device).unwrap();
    let out = learner.forward(&images(&wide, &device), &geometry).unwrap();
    let loss = out.stages[0].index.clone().sub_scalar(10.0).abs().mean();
    let grads = GradientsParams::from_grads(loss.backward(), &learner);
    let rows = |id, from: usize| {
        let grad = read_values(grads.get::<4>(id).expect("a gradient"), "grad").unwrap();
        let per_row = grad.len() / 16;
        grad[from * per_row..].iter().map(|g| g.abs()).sum::<f32>()
    };
    let down8 = rows(learner.features.down8.conv.weight.id, 8);
    assert!(
        down8 > 0.0 && down8.is_finite(),
        "down8's new rows: {down8}"
    );
    let out8 = learner.features.out8.conv.weight.id;
    let grad = read_values(grads.get::<4>(out8).unwrap(), "grad").unwrap();
    // Rows 2, 3 of every group of 4 are new.
    let new_rows: f32 = (0..4)
        .flat_map(|g| [g * 4 + 2, g * 4 + 3])
        .map(|row| {
            grad[row * 16..(row + 1) * 16]
                .iter()
                .map(|g| g.abs())
                .sum::<f32>()
        })
        .sum();
    assert!(
        new_rows > 0.0 && new_rows.is_finite(),
        "out8's new rows: {new_rows}"
    );
}

/// A network of `cued` saved and loaded grown into `grown` (one more option switched on):
/// its stages' first convolutions read `added` more input channels (as in a network built
/// with it), it answers as before, it needs the geometry of `grown`, its file does not load
/// back into `cued`, and the new inputs of the convolution `first` picks (`name`) get
/// gradients. Returns the two geometries and the frame's image pyramid for the option's own
/// checks.
fn grows_unchanged_and_learns(
    cued: &NetConfig,
    grown: &NetConfig,
    added: [usize; 3],
    first: fn(&CascadeNet) -> &Conv2d,
    name: &str,
) -> (CascadeGeometry, CascadeGeometry, ImagePyramid) {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let device = Device::flex();
    let small = CascadeNet::new(cued, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cued.safetensors");
    weights::save_module(&small, cued, &path).unwrap();
    let big = weights::load_cascade_grown(&path, grown, &device).unwrap();
    assert_eq!(big.config, *grown);
    let expected: Vec<usize> = first_inputs(&small)
        .iter()
        .zip(added)
        .map(|(c, a)| c + a)
        .collect();
    assert_eq!(first_inputs(&big).to_vec(), expected);
    assert_eq!(
        first_inputs(&CascadeNet::new(grown, &device).unwrap()),
        first_inputs(&big)
    );

    let tensors = images(cued, &device);
    let plain = CascadeGeometry::new(&ds.rig, cued, &hyps, &device).unwrap();
    let with = CascadeGeometry::new(&ds.rig, grown, &hyps, &device).unwrap();
    let before = small.forward(&tensors, &plain).unwrap();
    let after = big.forward(&tensors, &with).unwrap();
    assert_same_answers(&before, &after);
    // A network with it needs it, and its file does not load into one without.
    assert!(big.forward(&tensors, &plain).is_err());
    let big_path = dir.path().join("big.safetensors");
    weights::save_module(&big, grown, &big_path).unwrap();
    assert!(weights::load_cascade_grown(&big_path, cued, &device).is_err());

    // Its weights, zero at the start, get gradients.
    let autodiff = Device::flex().autodiff();
    let net = weights::load_cascade_grown(&path, grown, &autodiff).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, grown, &hyps, &autodiff).unwrap();
    let out = net.forward(&images(grown, &autodiff), &geometry).unwrap();
    let grads = GradientsParams::from_grads(pull_to_ten(out).backward(), &net);
    let k = added.iter().sum();
    assert_new_inputs_learn(&grads, first(&net), k, name);
    (plain, with, ImagePyramid::from_inputs(&tensors).unwrap())
}

#[test]
fn a_network_with_the_cue_grows_into_the_aggregated_cue_unchanged_and_learns_it() {
    let mut cued = micro_config();
    cued.cascade.zncc_cue = true;
    let mut aggregated = cued.clone();
    aggregated.cascade.coarse_cue_sgm = true;
    // Only the coarse stage's first convolution reads more: one channel per sphere.
    let (_, with, pyramid) = grows_unchanged_and_learns(
        &cued,
        &aggregated,
        [8, 0, 0],
        |net| &net.coarse.c0[0].conv,
        "coarse",
    );
    // Two cue channels; the aggregated one in [-1, 1].
    let cue = with.coarse_cue(Some(&pyramid)).unwrap().unwrap();
    assert_eq!(cue.dims(), [1, 2, 8, 4, 16]);
    let cue = read_values(cue, "cue").unwrap();
    assert!(cue[8 * 4 * 16..].iter().all(|z| (-1.0..=1.0).contains(z)));
    // It cannot be switched on without the cue it aggregates.
    let device = Device::flex();
    assert!(
        CascadeNet::new(&cued, &device)
            .unwrap()
            .with_coarse_cue_sgm()
            .is_ok()
    );
    let uncued = CascadeNet::new(&micro_config(), &device).unwrap();
    let err = uncued.with_coarse_cue_sgm().unwrap_err().to_string();
    assert!(err.contains("coarse_cue_sgm"), "{err}");
}
