//! Trains a network for your own rig: renders a small synthetic dataset (random objects in a
//! room or under a sky, with exact ground truth) through your cameras, trains the paper's
//! network at its small `tiny` size on it for a few epochs, then runs the trained weights on a
//! held-out frame. A minute or so in a release build; real training needs hundreds of frames
//! and thousands of steps (`omnimvs synth` and `omnimvs train`), but the calls are these.
//!
//! ```text
//! cargo run --release -p omnimvs-examples --example train_own_rig -- RIG OUT
//! ```
//!
//! RIG is `sunny` (the published 4-camera rig) or a reference `config.yaml` with your
//! calibration and `config.omnimvs_sweep_min_depth` (e.g. the reference implementation's
//! `itbt_sample/config.yaml`). OUT gets `data/` (the dataset: `config.yaml`, `camN/%05d.png`,
//! `omnidepth_gt_640/%05d.tiff`) and `run/` (the training run: `train_config.json`,
//! `metrics.jsonl`, `curves.png`, `model.safetensors` and `best.safetensors` with their
//! `.json`, `checkpoints/`). The weights work with `omnimvs infer --weights
//! OUT/run/best.safetensors` and `omnimvs train --resume OUT/run --epochs N` goes on.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use omnimvs_data::{Dataset, DepthEstimator, FrameRange};
use omnimvs_eval::metrics::{Protocol, protocol_metrics};
use omnimvs_net::weights::load_family;
use omnimvs_net::{Backend, NetConfig, NetEstimator, OmniMvsNet};
use omnimvs_sweep::LutCache;
use omnimvs_synth::rig::{load_rig, resize_rig};
use omnimvs_synth::{DatasetWriter, SceneKind, Shard, SynthOptions};
use omnimvs_train::{Optimizer, TrainConfig, Trainer};

const USAGE: &str = "usage: train_own_rig RIG OUT

Renders a small synthetic dataset for RIG (`sunny`, the published rig, or a reference
config.yaml) into OUT/data, trains the small `tiny` network on it into OUT/run and runs the
trained weights on a held-out frame.";

/// Frames 1..=TRAIN train the network, the next VAL frames validate it.
const TRAIN: u32 = 8;
const VAL: u32 = 2;
/// Passes over the training frames.
const EPOCHS: usize = 3;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [rig, out] = args.as_slice() else {
        eprintln!("{USAGE}");
        std::process::exit(2);
    };
    let (data_dir, run_dir) = (Path::new(out).join("data"), Path::new(out).join("run"));

    // The network: the paper's architecture at a quarter of its input size (`tiny`: 8
    // channels, N = 64 hypotheses, a 32x128 output), with as many cameras as the rig has.
    let mut net = NetConfig::tiny();

    // 1. The dataset. The rig and its minimum depth (the nearest sphere of the sweep), with
    // every camera's images rendered at the network's input size: the same rays, fewer
    // pixels, so rendering and loading are quick.
    let mut source = load_rig(rig).with_context(|| format!("reading the rig {rig}"))?;
    net.num_cameras = source.rig.len();
    source.rig = resize_rig(
        &source.rig,
        u32::try_from(net.input_height)?,
        u32::try_from(net.input_width)?,
    )?;
    // `things` scenes (OmniThings-like: random objects), seed 0: the same seed and frame give
    // the same files. Frames already complete are skipped, so a second run resumes.
    let frames = FrameRange::inclusive(1, TRAIN + VAL);
    let options = SynthOptions::new(SceneKind::Things, 0);
    let writer = DatasetWriter::create_with(&data_dir, &source, &options, &frames)?;
    let t0 = Instant::now();
    writer.run(&Shard::ALL.frames(&frames), |_| {})?;
    println!(
        "rendered {} frames of {} cameras into {} in {:.1} s",
        TRAIN + VAL,
        source.rig.len(),
        data_dir.display(),
        t0.elapsed().as_secs_f64()
    );

    // 2. Training: the L1 loss of the predicted against the true inverse-depth index, with
    // random camera order and small rig rotations as augmentation. The defaults are the
    // paper's recipe (SGD with momentum 0.9 at 0.003); Adam at 1e-3 learns faster in a few
    // steps. The learning rate drops to `lr_low` for the last third of the epochs.
    let config = TrainConfig {
        net,
        data: vec![data_dir.clone()],
        train_frames: Some((1, TRAIN)),
        val_frames: Some((TRAIN + 1, TRAIN + VAL)),
        epochs: EPOCHS,
        optimizer: Optimizer::Adam,
        lr: 1e-3,
        lr_low: 1e-4,
        ..TrainConfig::default()
    };
    let device = Backend::Cpu.device()?;
    // A new run; `Trainer::resume(&run_dir, None, &device)` continues one.
    let mut trainer = Trainer::<OmniMvsNet>::create(config, &run_dir, &device)
        .with_context(|| format!("starting a run in {}", run_dir.display()))?;
    let t0 = Instant::now();
    while trainer.state.epochs_done < EPOCHS {
        // One pass over the training frames, then validation, `metrics.jsonl`, `curves.png`
        // and a checkpoint; the closure sees every step.
        let record = trainer.train_epoch(&mut |_step| {})?;
        let val = record.val_reference.map_or(String::new(), |m| {
            format!(", validation MAE {:.2} % of N (reference protocol)", m.mae)
        });
        println!(
            "epoch {}/{EPOCHS}: {} steps in {:.1} s, training loss {:.2}{val}",
            record.epoch, record.steps, record.train_seconds, record.train_loss
        );
    }
    println!(
        "trained in {:.1} s; weights {}",
        t0.elapsed().as_secs_f64(),
        run_dir.join("best.safetensors").display()
    );

    // 3. The trained network on a held-out frame, as any other weights: loaded from the
    // file (its .json beside it says the sizes), prepared for the dataset's rig.
    let ds = Dataset::open(&data_dir)?;
    let weights = load_family(
        &run_dir.join("best.safetensors"),
        &NetConfig::tiny(),
        &device,
    )?;
    let (estimator, _lut_status) =
        NetEstimator::new(weights, &ds, &LutCache::default_location(), device, false)?;
    let frame = TRAIN + VAL;
    let est = estimator.estimate(&ds.read_frame(frame)?)?;
    let truth = ds
        .eval_truth(frame, &est.spec)?
        .context("the rendered frame has ground truth")?;
    let m = protocol_metrics(&est.index, &truth, est.spec.ndepth(), Protocol::Reference)?;
    println!(
        "frame {frame}: {}x{} in {:.2} s, MAE {:.2} % of N, >3 {:.1} % (reference protocol)",
        est.spec.height(),
        est.spec.width(),
        est.seconds,
        m.mae,
        m.over3_pct
    );
    Ok(())
}
