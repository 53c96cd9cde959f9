//! Training the cascade: gradients reach every stage's weights and it overfits one frame.
//! Uses the published rig of `sunny_single` from `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Mutex;

use burn::module::Module;
use burn::optim::GradientsParams;
use burn::tensor::Device;
use omnimvs_camera::Rig;
use omnimvs_data::Dataset;
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig};
use omnimvs_sweep::InvDepthHypotheses;
use omnimvs_train::{Learner, Optimizer, Sample, TrainConfig, TrainParts};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "../../omnimvs-net/tests/support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{micro_config, micro_images};

fn sunny_rig() -> (Rig, InvDepthHypotheses) {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    (ds.rig, hyps)
}

fn gt_on(h: usize, w: usize) -> GroundTruth {
    let index = (0..h * w)
        .map(|i| 4.0 + 20.0 * (i % w) as f32 / (w - 1) as f32 + 0.5 * ((i / w) % 3) as f32)
        .collect();
    GroundTruth {
        width: w,
        height: h,
        index,
        valid: (0..h * w).map(|i| i % 7 != 0).collect(),
    }
}

fn micro_sample(config: &NetConfig) -> Sample {
    let [coarse, mid, fine] = config.cascade_sizes();
    Sample {
        source: 0,
        frame: 1,
        rotation: 0,
        images: micro_images(config),
        gt: gt_on(fine[0], fine[1]),
        stage_gt: vec![gt_on(coarse[0], coarse[1]), gt_on(mid[0], mid[1])],
        window: None,
    }
}

/// Seeding the device's generator and drawing the initial weights, one test at a time: the
/// tests of this file run in parallel threads of one process and share the generator, so
/// without this a test's weights would depend on how its draws interleave with the others'
/// (one CI run drew weights whose stride-8 branch did not move in 16 steps).
fn seeded<T>(init: impl FnOnce() -> T) -> T {
    static INIT: Mutex<()> = Mutex::new(());
    let _guard = INIT
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    init()
}

fn seeded_learner(config: &TrainConfig, device: &Device) -> Learner<CascadeNet> {
    seeded(|| {
        let learner = Learner::<CascadeNet>::for_model(config, device).unwrap();
        // burn draws a parameter's initial values when it is first read: read them all here.
        let _ = learner.net.clone().into_record();
        learner
    })
}

/// A learner of `config` (seeded) on the published rig, its geometry and the micro sample.
fn learner_on_sunny(config: &TrainConfig) -> (Learner<CascadeNet>, CascadeGeometry, Sample) {
    let (rig, hyps) = sunny_rig();
    let learner = seeded_learner(config, &Device::flex());
    let geometry = CascadeGeometry::new(&rig, &config.net, &hyps, &learner.device).unwrap();
    (learner, geometry, micro_sample(&config.net))
}

/// Steps `learner` on `sample` `1 + more` times; the first and the last loss.
fn first_and_last_loss(
    learner: &mut Learner<CascadeNet>,
    sample: &Sample,
    geometry: &CascadeGeometry,
    more: usize,
) -> (f32, f32) {
    let first = learner.step(sample, geometry, &[], 0.01).unwrap();
    let mut last = first;
    for _ in 0..more {
        last = learner.step(sample, geometry, &[], 0.01).unwrap();
    }
    (first, last)
}

/// Asserts that of the weights read `before` and `after` training, the first `frozen` stayed
/// and the others, `what`, moved.
fn assert_only_the_rest_moved(before: &[Vec<f32>], after: &[Vec<f32>], frozen: usize, what: &str) {
    for (i, (a, b)) in before.iter().zip(after).enumerate() {
        if i < frozen {
            assert_eq!(a, b, "frozen weights {i} moved");
        } else {
            assert_ne!(a, b, "{what} weights {i} did not move");
        }
    }
}

/// Asserts that training only `parts` (a stage of the cascade) of the paper's network is
/// refused, naming the field and the cascade.
fn assert_the_paper_network_refuses(parts: TrainParts, device: &Device) {
    let mut paper = TrainConfig {
        net: NetConfig::tiny(),
        ..TrainConfig::default()
    };
    paper.train_only = parts;
    // Under the lock too: it seeds the generator the other tests draw their weights from.
    let err = seeded(|| Learner::<omnimvs_net::OmniMvsNet>::for_model(&paper, device))
        .err()
        .expect("training a stage of the paper's network alone is refused")
        .to_string();
    assert!(
        err.contains("train_only") && err.contains("cascade"),
        "{err}"
    );
}

fn train_config(seed: u64) -> TrainConfig {
    TrainConfig {
        net: micro_config(),
        seed,
        optimizer: Optimizer::Adam,
        ..TrainConfig::default()
    }
}

#[test]
fn gradients_reach_every_stage_and_it_overfits_one_frame() {
    let (rig, hyps) = sunny_rig();
    let config = train_config(3);
    let device = Device::flex();
    let mut learner = seeded_learner(&config, &device);
    let geometry = CascadeGeometry::new(&rig, &config.net, &hyps, &learner.device).unwrap();
    let sample = micro_sample(&config.net);

    let loss = learner.loss(&sample, &geometry, &[]).unwrap();
    let grads = GradientsParams::from_grads(loss.backward(), &learner.net);
    let net = &learner.net;
    let norm = |name: &str, grad: Option<Vec<f32>>| {
        let grad = grad.unwrap_or_else(|| panic!("no gradient for {name}"));
        let norm: f32 = grad.iter().map(|g| g.abs()).sum();
        assert!(
            norm > 0.0 && norm.is_finite(),
            "{name}: gradient norm {norm}"
        );
    };
    let read4 = |id| grads.get::<4>(id).map(|g| read_values(g, "grad").unwrap());
    norm("features.conv0", read4(net.features.conv0.conv.weight.id));
    norm("features.out2", read4(net.features.out2.conv.weight.id));
    norm("features.out8", read4(net.features.out8.conv.weight.id));
    norm("coarse.out", read4(net.coarse.out.conv.weight.id));
    norm("mid.out", read4(net.mid.out.conv.weight.id));
    norm("fine.out", read4(net.fine.out.conv.weight.id));

    let first = learner.step(&sample, &geometry, &[], 0.01).unwrap();
    let mut last = first;
    let mut steps = 1;
    while steps < 80 && last > 0.3 * first {
        last = learner.step(&sample, &geometry, &[], 0.01).unwrap();
        steps += 1;
    }
    assert!(
        last < 0.3 * first,
        "loss {first} -> {last} after {steps} steps: the cascade does not fit one frame"
    );
}

#[test]
fn training_only_the_upsampling_moves_the_selectors_and_nothing_else() {
    let mut config = train_config(5);
    config.net.cascade.convex_upsampling = true;
    config.train_only = TrainParts::Upsampling;
    let device = Device::flex();
    let (mut learner, geometry, sample) = learner_on_sunny(&config);
    let weights = |net: &CascadeNet| {
        let selector = net.up_mid.as_ref().unwrap();
        [
            net.features.conv0.conv.weight.val(),
            net.coarse.out.conv.weight.val(),
            net.mid.out.conv.weight.val(),
            net.fine.convs[0].conv.weight.val(),
            selector.out.weight.val(),
            net.up_fine.as_ref().unwrap().out.weight.val(),
        ]
        .map(|t| read_values(t, "weights").unwrap())
    };
    let before = weights(&learner.net);
    let (first, last) = first_and_last_loss(&mut learner, &sample, &geometry, 5);
    assert_only_the_rest_moved(&before, &weights(&learner.net), 4, "selector");
    assert!(
        last < first,
        "the centres' loss did not fall: {first} -> {last}"
    );

    // With the half grid's selector alone (the bundled model's configuration), that one
    // trains and the rest stays.
    let mut half = train_config(5);
    half.net.cascade.convex_upsampling = true;
    half.net.cascade.convex_upsampling_full = false;
    half.train_only = TrainParts::Upsampling;
    let (mut learner, geometry, sample) = learner_on_sunny(&half);
    let half_weights = |net: &CascadeNet| {
        assert!(net.up_fine.is_none());
        [
            net.features.conv0.conv.weight.val(),
            net.mid.out.conv.weight.val(),
            net.fine.convs[0].conv.weight.val(),
            net.up_mid.as_ref().unwrap().out.weight.val(),
        ]
        .map(|t| read_values(t, "weights").unwrap())
    };
    let before = half_weights(&learner.net);
    let (first, last) = first_and_last_loss(&mut learner, &sample, &geometry, 5);
    assert_only_the_rest_moved(
        &before,
        &half_weights(&learner.net),
        3,
        "half-grid selector",
    );
    assert!(
        last < first,
        "the centres' loss did not fall: {first} -> {last}"
    );

    // A network without the selectors has nothing to train.
    let mut plain = train_config(5);
    plain.train_only = TrainParts::Upsampling;
    let err = seeded(|| Learner::<CascadeNet>::for_model(&plain, &device))
        .err()
        .expect("training only absent selectors is refused")
        .to_string();
    assert!(
        err.contains("train_only") && err.contains("convex_upsampling"),
        "{err}"
    );
}

#[test]
fn training_only_the_coarse_stage_moves_its_weights_and_nothing_else() {
    let mut config = train_config(7);
    config.net.cascade.convex_upsampling = true;
    config.train_only = TrainParts::Coarse;
    let device = Device::flex();
    let (mut learner, geometry, sample) = learner_on_sunny(&config);
    // Frozen first: the stride-2 and stride-4 features, the refinement stages, the
    // selectors; then the coarse stage's own weights.
    let weights = |net: &CascadeNet| {
        [
            net.features.conv0.conv.weight.val(),
            net.features.out2.conv.weight.val(),
            net.features.res4[1].conv.weight.val(),
            net.features.out4.conv.weight.val(),
            net.mid.out.conv.weight.val(),
            net.fine.convs[0].conv.weight.val(),
            net.up_mid.as_ref().unwrap().out.weight.val(),
            net.features.down8.conv.weight.val(),
            net.features.out8.conv.weight.val(),
            net.coarse.out.conv.weight.val(),
        ]
        .map(|t| read_values(t, "weights").unwrap())
    };
    let before = weights(&learner.net);
    let coarse_error = |learner: &Learner<CascadeNet>| {
        let out = learner
            .net
            .forward_coarse(&learner.image_tensors(&sample), &geometry, false)
            .unwrap();
        let index = read_values(out.index, "coarse index").unwrap();
        let gt = &sample.stage_gt[0];
        let (sum, n) = index
            .iter()
            .zip(&gt.index)
            .zip(&gt.valid)
            .filter(|(_, v)| **v)
            .fold((0.0, 0), |(s, n), ((i, t), _)| (s + (i - t).abs(), n + 1));
        sum / n as f32
    };
    let start = coarse_error(&learner);
    let (first, last) = first_and_last_loss(&mut learner, &sample, &geometry, 15);
    assert_only_the_rest_moved(&before, &weights(&learner.net), 7, "coarse-stage");
    assert!(
        last < first,
        "the coarse loss did not fall: {first} -> {last}"
    );
    let end = coarse_error(&learner);
    assert!(
        end < start,
        "the coarse stage's error did not fall: {start} -> {end}"
    );

    // The paper's network has no coarse stage to train alone.
    assert_the_paper_network_refuses(TrainParts::Coarse, &device);
}

#[test]
fn training_only_the_half_stage_moves_its_weights_and_nothing_else() {
    let mut config = train_config(11);
    config.net.cascade.convex_upsampling = true;
    config.net.cascade.zncc_cue = true;
    config.net.cascade.coarse_cue_oversample = 2;
    config.train_only = TrainParts::Mid;
    let device = Device::flex();
    let (mut learner, geometry, sample) = learner_on_sunny(&config);
    // Frozen first: the features, the coarse stage, the full-resolution stage, the
    // selectors; then the half stage's own weights.
    let weights = |net: &CascadeNet| {
        [
            net.features.conv0.conv.weight.val(),
            net.features.out4.conv.weight.val(),
            net.features.out8.conv.weight.val(),
            net.coarse.out.conv.weight.val(),
            net.fine.convs[0].conv.weight.val(),
            net.up_mid.as_ref().unwrap().out.weight.val(),
            net.mid.convs[0].conv.weight.val(),
            net.mid.out.conv.weight.val(),
        ]
        .map(|t| read_values(t, "weights").unwrap())
    };
    let before = weights(&learner.net);
    let (first, last) = first_and_last_loss(&mut learner, &sample, &geometry, 10);
    assert_only_the_rest_moved(&before, &weights(&learner.net), 6, "half-stage");
    assert!(last < first, "the loss did not fall: {first} -> {last}");

    // The paper's network has no half stage to train alone.
    assert_the_paper_network_refuses(TrainParts::Mid, &device);
}

#[test]
fn training_only_the_full_stage_moves_its_weights_and_nothing_else() {
    let mut config = train_config(13);
    config.net.cascade.convex_upsampling = true;
    config.net.cascade.convex_upsampling_full = false;
    config.train_only = TrainParts::Fine;
    let device = Device::flex();
    let (mut learner, geometry, sample) = learner_on_sunny(&config);
    // Frozen first: the stem, the stride-4 and stride-8 features, the coarse and half
    // stages, the half grid's selector; then the full stage's own weights and the stride-2
    // projection it reads.
    let weights = |net: &CascadeNet| {
        [
            net.features.conv0.conv.weight.val(),
            net.features.conv2.conv.weight.val(),
            net.features.out4.conv.weight.val(),
            net.features.out8.conv.weight.val(),
            net.coarse.out.conv.weight.val(),
            net.mid.convs[0].conv.weight.val(),
            net.up_mid.as_ref().unwrap().out.weight.val(),
            net.features.out2.conv.weight.val(),
            net.fine.convs[0].conv.weight.val(),
            net.fine.out.conv.weight.val(),
        ]
        .map(|t| read_values(t, "weights").unwrap())
    };
    let before = weights(&learner.net);
    let (first, last) = first_and_last_loss(&mut learner, &sample, &geometry, 10);
    assert_only_the_rest_moved(&before, &weights(&learner.net), 7, "full-stage");
    assert!(last < first, "the loss did not fall: {first} -> {last}");

    // The paper's network has no full stage to train alone.
    assert_the_paper_network_refuses(TrainParts::Fine, &device);
}

/// Validation on a CPU runs the cascade's host path (`Trainable::on_host`: batch norms folded,
/// convolutions and correlation on the host, as `omnimvs infer`): the index map is the device
/// path's to float rounding, for a network whose batch norms hold statistics of their own.
#[test]
fn validation_on_the_host_path_predicts_as_the_device_path() {
    use burn::module::Param;
    use burn::tensor::{Distribution, Tensor};
    use omnimvs_train::{RotationSet, SampleSource, Trainable};

    let mut config = micro_config();
    config.cascade.zncc_cue = true;
    config.cascade.stage_gates = true;
    let device = Device::flex();
    let mut net = seeded(|| CascadeNet::new(&config, &device).unwrap());
    // Batch-norm statistics other than the identity, so that folding them matters.
    let c = net.features.conv2.bn.as_mut().unwrap();
    let n = c.gamma.val().dims()[0];
    c.gamma = Param::from_tensor(Tensor::random(
        [n],
        Distribution::Uniform(0.5, 1.5),
        &device,
    ));
    c.beta = Param::from_tensor(Tensor::random(
        [n],
        Distribution::Uniform(-0.2, 0.2),
        &device,
    ));
    let net = net.valid();
    let source = SampleSource::open(
        &sample_dir("sunny_single"),
        &config,
        RotationSet::new(1, 0.0, 1),
    )
    .unwrap();
    let images: Vec<Tensor<4>> = micro_images(&config)
        .into_iter()
        .map(|img| {
            Tensor::from_data(
                burn::tensor::TensorData::new(img, [1, 1, config.input_height, config.input_width]),
                &device,
            )
        })
        .collect();
    let device_geometry = net.validation_geometry(&source, &device, false).unwrap();
    let on_device = net.predict(&images, &device_geometry, &source).unwrap();
    let host = net.clone().on_host();
    assert!(host.features.conv2.host.is_some(), "the host path is taken");
    let host_geometry = host.validation_geometry(&source, &device, true).unwrap();
    assert!(host_geometry.host_correlation);
    let on_host = host.predict(&images, &host_geometry, &source).unwrap();
    let a = read_values(on_device, "device").unwrap();
    let b = read_values(on_host, "host").unwrap();
    let d = micro_cascade::max_difference(&a, &b);
    assert!(d < 1e-3, "index maps differ by {d}");
}

/// One cascade learns from rigs of different camera counts in turn (the published rig's first
/// two and three cameras, and all four): the loss falls on each, from the same weights.
#[test]
fn one_cascade_trains_on_rigs_of_two_three_and_four_cameras() {
    let (rig, hyps) = sunny_rig();
    let config = train_config(11);
    let device = Device::flex();
    let mut learner = seeded_learner(&config, &device);
    let setups: Vec<(CascadeGeometry, Sample)> = [2, 3, 4]
        .into_iter()
        .map(|count| {
            let sub = Rig::new(rig.cameras[..count].to_vec());
            let geometry = CascadeGeometry::new(&sub, &config.net, &hyps, &device).unwrap();
            let net = NetConfig {
                num_cameras: count,
                ..config.net.clone()
            };
            (geometry, micro_sample(&net))
        })
        .collect();
    let first: Vec<f32> = setups
        .iter()
        .map(|(g, s)| read_values(learner.loss(s, g, &[]).unwrap(), "loss").unwrap()[0])
        .collect();
    for _ in 0..15 {
        for (geometry, sample) in &setups {
            learner.step(sample, geometry, &[], 0.01).unwrap();
        }
    }
    for ((geometry, sample), first) in setups.iter().zip(first) {
        let last = read_values(learner.loss(sample, geometry, &[]).unwrap(), "loss").unwrap()[0];
        let count = sample.images.len();
        println!("{count} cameras: loss {first:.3} -> {last:.3}");
        assert!(last < 0.7 * first, "{count} cameras: {first} -> {last}");
    }
}
