//! Training learns and resumes exactly: overfitting one tiny frame, and the next-step loss
//! after a checkpoint round trip equals the uninterrupted run's.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::Mutex;

use burn::module::Module;
use burn::store::{BurnpackStore, ModuleSnapshot};
use burn::tensor::Device;
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::synthetic::synthetic_grids;
use omnimvs_net::{Layout, NetConfig};
use omnimvs_train::{Learner, Sample, TrainConfig, TrainParts};

/// A learner of `config` whose initial weights are drawn under one lock: the tests of this file
/// run in parallel and `Device::seed` seeds a generator they share, so without it a test's
/// weights depend on the other tests' timing (two CI runs drew weights whose three steps moved
/// the frozen-statistics loss by less than that test's 1e-5). burn draws a parameter when it
/// is first read, so every parameter is read under the lock too.
fn new_learner(config: &TrainConfig, device: &Device) -> Learner {
    static INIT: Mutex<()> = Mutex::new(());
    let _guard = INIT
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let learner = Learner::new(config, device).unwrap();
    // burn draws a parameter's initial values when it is first read: read them all here.
    let _ = learner.net.clone().into_record();
    learner
}

/// The smallest network the decoder allows: `N = 32`, a `32 x 32` output, two cameras.
fn micro_config() -> NetConfig {
    NetConfig {
        channels: 4,
        num_invdepth: 32,
        out_height: 32,
        out_width: 32,
        phi_deg: 45.0,
        num_cameras: 2,
        input_height: 24,
        input_width: 32,
        layout: Layout::Iccv,
        ..NetConfig::tiny()
    }
}

/// A frame with textured inputs and a smooth ground truth (index 4..28 across columns).
fn micro_sample(net: &NetConfig) -> Sample {
    let images = (0..net.num_cameras)
        .map(|cam| {
            (0..net.input_height * net.input_width)
                .map(|i| {
                    let (r, c) = ((i / net.input_width) as f32, (i % net.input_width) as f32);
                    ((0.7 * c + 1.3 * r + cam as f32).sin() + (0.31 * c * r).cos()) * 0.8
                })
                .collect()
        })
        .collect();
    let (h, w) = (net.out_height, net.out_width);
    let index: Vec<f32> = (0..h * w)
        .map(|i| 4.0 + 24.0 * (i % w) as f32 / (w - 1) as f32 + 0.3 * ((i / w) % 3) as f32)
        .collect();
    let valid = (0..h * w).map(|i| i % 7 != 0).collect();
    Sample {
        source: 0,
        frame: 1,
        rotation: 0,
        images,
        gt: GroundTruth {
            width: w,
            height: h,
            index,
            valid,
        },
        stage_gt: Vec::new(),
        window: None,
    }
}

fn train_config(seed: u64) -> TrainConfig {
    TrainConfig {
        net: micro_config(),
        seed,
        ..TrainConfig::default()
    }
}

#[test]
fn overfits_one_tiny_frame() {
    let config = train_config(1);
    let mut learner = new_learner(&config, &Device::flex());
    let sample = micro_sample(&config.net);
    let taps = learner.taps(&synthetic_grids(&config.net));
    let order = [0, 1];
    let first = learner.step(&sample, &taps, &order, 0.01).unwrap();
    let mut last = first;
    let mut steps = 1;
    while steps < 150 && last > 0.2 * first {
        last = learner.step(&sample, &taps, &order, 0.01).unwrap();
        steps += 1;
    }
    assert!(
        last < 0.2 * first,
        "loss {first} -> {last} after {steps} steps: the network does not fit one frame"
    );
}

#[test]
fn resume_gives_the_uninterrupted_next_step_loss() {
    let config = train_config(2);
    let device = Device::flex();
    let sample = micro_sample(&config.net);
    let grids = synthetic_grids(&config.net);
    let dir = tempfile::tempdir().unwrap();

    let mut run = new_learner(&config, &device);
    let taps = run.taps(&grids);
    for order in [[0, 1], [1, 0]] {
        run.step(&sample, &taps, &order, 0.01).unwrap();
    }
    run.save_checkpoint(dir.path()).unwrap();
    let expected: Vec<f32> = (0..2)
        .map(|_| run.step(&sample, &taps, &[1, 0], 0.01).unwrap())
        .collect();

    // Another seed: everything must come from the checkpoint.
    let mut resumed = new_learner(&train_config(99), &device);
    resumed.load_checkpoint(dir.path()).unwrap();
    let taps = resumed.taps(&grids);
    let actual: Vec<f32> = (0..2)
        .map(|_| resumed.step(&sample, &taps, &[1, 0], 0.01).unwrap())
        .collect();
    for (e, a) in expected.iter().zip(&actual) {
        assert!(
            (e - a).abs() <= 1e-5 * e.abs().max(1.0),
            "{expected:?} vs {actual:?}"
        );
    }

    // The optimiser state matters: without the momentum the second loss differs.
    let mut weights_only = new_learner(&train_config(99), &device);
    weights_only.load_checkpoint(dir.path()).unwrap();
    weights_only.optim = burn::optim::SgdConfig::new()
        .with_momentum(Some(burn::optim::momentum::MomentumConfig {
            momentum: 0.9,
            dampening: 0.0,
            nesterov: false,
        }))
        .init();
    let taps = weights_only.taps(&grids);
    let fresh: Vec<f32> = (0..2)
        .map(|_| weights_only.step(&sample, &taps, &[1, 0], 0.01).unwrap())
        .collect();
    assert!((fresh[0] - expected[0]).abs() < 1e-5);
    assert!(
        (fresh[1] - expected[1]).abs() > 1e-4,
        "momentum not restored? {fresh:?} vs {expected:?}"
    );
}

#[test]
fn checkpoints_are_burns_own_files_written_whole() {
    let config = train_config(3);
    let mut learner = new_learner(&config, &Device::flex());
    let sample = micro_sample(&config.net);
    let taps = learner.taps(&synthetic_grids(&config.net));
    learner.step(&sample, &taps, &[0, 1], 0.01).unwrap(); // momentum buffers to save
    let dir = tempfile::tempdir().unwrap();
    learner.save_checkpoint(dir.path()).unwrap();
    // Only the two files: the temporary files of the atomic writes are gone.
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["model.bpk", "optim.bpk"]);
    // Byte for byte what burn's own file writers give: old run folders still resume.
    let burn_dir = tempfile::tempdir().unwrap();
    let mut store = BurnpackStore::from_file(burn_dir.path().join("model.bpk"))
        .auto_extension(false)
        .overwrite(true);
    learner.net.save_into(&mut store).unwrap();
    learner
        .optim
        .save(burn_dir.path().join("optim.bpk"))
        .unwrap();
    for name in names {
        assert_eq!(
            std::fs::read(dir.path().join(&name)).unwrap(),
            std::fs::read(burn_dir.path().join(&name)).unwrap(),
            "{name}"
        );
    }
}

/// Loss of `sample` by the learner's network in training mode (autodiff device) and by its
/// inference copy (batch norms on running statistics), before any step, after three, and after
/// three more and a checkpoint saved and loaded back (which restores tensors, not the flags).
fn train_and_inference_losses(frozen: bool) -> Vec<(f32, f32)> {
    use omnimvs_net::model::SweepTaps;
    use omnimvs_train::Trainable;
    let config = TrainConfig {
        frozen_norm_stats: frozen,
        ..train_config(3)
    };
    let mut learner = new_learner(&config, &Device::flex());
    let sample = micro_sample(&config.net);
    let grids = synthetic_grids(&config.net);
    let taps = learner.taps(&grids);
    let order = [0, 1];
    let plain = learner.device.clone().without_autodiff();
    let plain_taps = SweepTaps::for_grids(&grids, config.net.feature_size(), &plain);
    let dir = tempfile::tempdir().unwrap();
    let mut losses = Vec::new();
    for round in 0..3 {
        if round == 2 {
            learner.save_checkpoint(dir.path()).unwrap();
            learner.load_checkpoint(dir.path()).unwrap();
        }
        let train = learner
            .loss(&sample, &taps, &order)
            .unwrap()
            .into_scalar::<f32>();
        let images = learner.image_tensors_on(&sample, &plain);
        let inference = learner
            .inference_net()
            .loss(&images, &plain_taps, &order, &sample, TrainParts::All)
            .unwrap()
            .into_scalar::<f32>();
        losses.push((train, inference));
        for _ in 0..3 {
            learner.step(&sample, &taps, &order, 0.01).unwrap();
        }
    }
    losses
}

#[test]
fn frozen_norm_statistics_train_as_inference_runs() {
    // Frozen: training normalises as inference does, before and after steps and a
    // checkpoint round trip (the steps leave the running statistics alone, and the weights learn: slowly here, as a fresh
    // network's running statistics, mean 0 and variance 1, do not normalise its activations;
    // 3e-5 in 3 steps where batch statistics give 0.4).
    let frozen = train_and_inference_losses(true);
    for (train, inference) in &frozen {
        assert!(
            (train - inference).abs() <= 1e-4 * inference.abs().max(1.0),
            "frozen statistics: training loss {train}, inference loss {inference}"
        );
    }
    assert!(
        (frozen[0].0 - frozen[1].0).abs() > 1e-5,
        "the steps did not change the network: {frozen:?}"
    );
    // Not frozen: training normalises with the batch's statistics, which differ.
    let batch = train_and_inference_losses(false);
    assert!(
        (batch[0].0 - batch[0].1).abs() > 1e-3,
        "batch statistics should differ from fresh running ones: {batch:?}"
    );
}
