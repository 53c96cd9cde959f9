//! `omnimvs train`: end-to-end training of the network on dataset folders.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use burn::tensor::Device;
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_core::fs::write_atomic;
use omnimvs_data::FrameRange;
use omnimvs_eval::metrics::Metrics;
use omnimvs_net::{Backend, CascadeNet, Family, NetConfig, OmniMvsNet};
use omnimvs_train::mccnn::{CostTrainConfig, CostTrainer};
use omnimvs_train::sweepnet::{SweepTrainConfig, SweepTrainer};
use omnimvs_train::trainer::read_run_config;
use omnimvs_train::{
    EpochRecord, Optimizer, PhotometricAugment, Selection, StepInfo, TrainConfig, TrainParts,
    Trainable, Trainer,
};

use crate::args::{Preset, parse_backend};

/// Train a network (the paper's or the cascade) end to end, resumably.
///
/// Train a network end to end: the paper's (`--preset tiny|paper`, sections 3.3 and 5.1: L1
/// loss between the predicted and the rounded ground-truth index over valid pixels) or the
/// cascade (`--preset cascade`: L1 of each of its three stages against the exact index on
/// its grid, weights 0.5, 1, 2). SGD with momentum 0.9 (or Adam with --optimizer adam),
/// learning rate --lr then --lr-low for the last third of the epochs, random cyclic camera
/// order and small rig rotations (a fixed seeded set of precomputed rotations, ground truth
/// rotated to match). A loader thread prepares samples while the step runs.
///
/// Writes RUN_DIR/train_config.json, metrics.jsonl (one line per epoch), curves.png,
/// model.safetensors (+ .json: last epoch), best.safetensors (lowest validation MAE) and
/// checkpoints/ (model + optimiser, every epoch, atomic): kill it at any moment and
/// `--resume RUN_DIR` continues from the last finished epoch exactly.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folders with ground truth, comma-separated.
    #[arg(long, value_delimiter = ',', required_unless_present = "resume")]
    pub data: Vec<PathBuf>,
    /// Network: tiny or paper (the paper's network), or cascade (the coarse-to-fine
    /// network at the paper's output grid).
    #[arg(long, value_enum, default_value_t = Preset::Tiny)]
    pub preset: Preset,
    /// Optimiser: sgd (the paper's, with --momentum) or adam (--momentum is its beta 1).
    #[arg(long, value_enum, default_value = "sgd")]
    pub optimizer: OptimizerArg,
    /// Run folder (new). With --resume, the run folder to continue.
    #[arg(long, required_unless_present = "resume")]
    pub out: Option<PathBuf>,
    /// Continue the run in this folder from its last checkpoint (its configuration is
    /// reused; --epochs may raise the total).
    #[arg(long, conflicts_with_all = ["data", "out", "init"])]
    pub resume: Option<PathBuf>,
    /// Start from these weights (fine-tuning, the paper's "-ft"): .safetensors with its
    /// .json, or a reference PyTorch checkpoint.
    #[arg(long)]
    pub init: Option<PathBuf>,
    /// Number of epochs.
    #[arg(long)]
    pub epochs: Option<usize>,
    /// Learning rate of the first epochs.
    #[arg(long, default_value_t = 0.003)]
    pub lr: f64,
    /// Learning rate of the last epochs (default: a tenth of --lr, so 0.0003 after the default
    /// 0.003 as in the paper; never above --lr unless asked).
    #[arg(long)]
    pub lr_low: Option<f64>,
    /// Epochs at --lr-low (default: a third of the epochs).
    #[arg(long)]
    pub low_lr_epochs: Option<usize>,
    /// SGD momentum (Adam's beta 1).
    #[arg(long, default_value_t = 0.9)]
    pub momentum: f64,
    /// Seed of the initial weights, shuffling and augmentation.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Training frames, A..B (default: every frame outside the validation frames).
    #[arg(long)]
    pub train_frames: Option<FrameRange>,
    /// Validation frames, A..B (default: the last 10% of each dataset's frames).
    #[arg(long)]
    pub val_frames: Option<FrameRange>,
    /// Precomputed rig rotations for augmentation, identity included (1: off).
    #[arg(long, default_value_t = 8)]
    pub rotations: usize,
    /// Largest augmentation rotation, degrees.
    #[arg(long, default_value_t = 5.0)]
    pub max_rotation_deg: f64,
    /// Keep the rig's camera order at the concatenation (no permutation augmentation).
    #[arg(long)]
    pub no_permute: bool,
    /// Steps per epoch at most (default: every training frame once).
    #[arg(long)]
    pub max_steps: Option<usize>,
    /// Validation frames per epoch at most.
    #[arg(long)]
    pub max_val_frames: Option<usize>,
    /// Train the cascade's refinement stages on a window of this many output columns at a
    /// random longitude every step (cuts their cost in proportion; the coarse stage always
    /// sees the whole panorama). Also taken with --resume, from then on.
    #[arg(long)]
    pub column_window: Option<usize>,
    /// Per-camera photometric augmentation of the training images, as real cameras differ:
    /// exposure with clipping, gamma, vignetting, blur and sensor noise (ranges in
    /// `train_config.json`, field `photometric`). Also taken with --resume: `on` starts it
    /// from the next epoch, `off` stops it.
    #[arg(long, value_enum)]
    pub photometric: Option<Switch>,
    /// Batch norms normalise with their running statistics during training too and leave them
    /// as they are (`frozen_norm_stats`; their scale and shift still learn): for fine-tuning
    /// with --init, where one window's batch statistics drift validation away.
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub frozen_norm_stats: Option<Switch>,
    /// The validation MAE that picks `best.safetensors` (`select_by`): `with-sky` (sky scored
    /// as index 0, what training asks for) or `reference` (the reference's protocol, sky not
    /// scored: the paper's tables).
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub select_by: Option<SelectArg>,
    /// Cascade: context residual pairs at stride 8, dilated 4 and 8 in turn (`context_pairs`
    /// of the configuration; 0 in the first cascades). They start as the identity, so --init
    /// with a network without them goes on from its answer.
    #[arg(long, conflicts_with = "resume")]
    pub context_pairs: Option<usize>,
    /// Cascade: channels of the stride-8 features that the coarse stage correlates
    /// (`feature_channels[2]`, 16 until `cascade-21`); a multiple of the coarse stage's 8
    /// groups, at most 64. --init weights of a narrower network widen into it answering as
    /// before (up to a perturbation of about 1 % of the coarse correlation).
    #[arg(long, conflicts_with = "resume")]
    pub coarse_feature_channels: Option<usize>,
    /// Cascade: spheres of the coarse cost volume (`coarse_spheres`, 32 in the preset). --init
    /// weights over other spheres are resampled along them: the coarse stage's first and
    /// scoring convolutions, every other weight kept.
    #[arg(long, conflicts_with = "resume")]
    pub coarse_spheres: Option<usize>,
    /// Cascade with the photometric cue: the grid the coarse stage's cue is matched on, 1 the
    /// coarse grid (quarter-size images), 2 the half-resolution grid (half-size images, 2 x 2
    /// means; `coarse_cue_oversample`, from `cascade-22`). No weight depends on it.
    #[arg(long, conflicts_with = "resume")]
    pub coarse_cue_oversample: Option<usize>,
    /// Cascade with the photometric cue: inverse depths the coarse cue is matched at per
    /// coarse sphere (1, 3 or 5, evenly tiling its interval; the sphere takes the best;
    /// `coarse_cue_depths`, from `cascade-23`). No weight depends on it.
    #[arg(long, conflicts_with = "resume")]
    pub coarse_cue_depths: Option<usize>,
    /// Cascade with the photometric cue: a second coarse cue channel, the cue aggregated by
    /// semi-global matching over the coarse grid (`coarse_cue_sgm`, from `cascade-24`).
    /// --init weights without it grow into it answering as before (zero weights for it).
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub coarse_cue_sgm: Option<Switch>,
    /// Threads preparing the training samples (decoding the images, augmenting; 1 by
    /// default). The samples and their order do not depend on it: more is for a GPU, whose
    /// steps outrun one thread. Also taken by --resume.
    #[arg(long)]
    pub loader_threads: Option<usize>,
    /// Cascade: refinement stages gated between their answer and their centre
    /// (`stage_gates`; off in the first cascades). Taken with --init like --context-pairs.
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub stage_gates: Option<Switch>,
    /// Cascade: the photometric cue, the ZNCC of the cameras' own images at every stage's
    /// samples as one more channel of its volume (`zncc_cue`; off before `cascade-8`). Its
    /// weights start at zero, so --init with a network without it goes on from its answer.
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub zncc_cue: Option<Switch>,
    /// Cascade: weight of a cross-entropy between the coarse stage's distribution over its
    /// spheres and a Laplacian around the ground truth, beside the stages' L1
    /// (`coarse_distribution_weight`; 0 in the first cascades): it asks the coarse stage for
    /// one peak at the truth, not just a right mean.
    #[arg(long, conflicts_with = "resume")]
    pub coarse_distribution: Option<f64>,
    /// Cascade: the same cross-entropy for each refinement stage over its per-pixel
    /// hypotheses (`refine_distribution_weight`; 0 in the first cascades).
    #[arg(long, conflicts_with = "resume")]
    pub refine_distribution: Option<f64>,
    /// Cascade: weight of sky pixels in every stage's losses, against 1 for the others
    /// (`sky_loss_weight`; 1 before `cascade-11`). The reference's metrics do not score sky;
    /// below 1, a frame's large sky pulls near objects and edges toward far less.
    #[arg(long, conflicts_with = "resume")]
    pub sky_weight: Option<f64>,
    /// Cascade: learnt (convex) upsampling of each stage's answer to the next stage's grid
    /// (`convex_upsampling`; off before `cascade-13`): the finer grid's centres are
    /// softmax-weighted means of the 3 x 3 coarser pixels around each parent, the weights
    /// read from the finer features' matching at each of them, instead of the bilinear mean
    /// that blends the two sides of a depth edge. The selectors start near the bilinear
    /// weights, so --init with a network without them goes on from near its answer. `half`:
    /// on the half-resolution grid only (`convex_upsampling_full` off; the full grid's
    /// selector is the dearer one), which also leaves an --init network's full-grid selector
    /// out.
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub convex_upsampling: Option<UpsamplingArg>,
    /// Cascade: spacing of the half- and full-resolution stages' hypotheses around their
    /// centres, in index units of N, `HALF,FULL` (`stage_intervals`; 2,1 before `cascade-18`).
    /// No weight depends on it, so --init weights of another spacing load as they are.
    #[arg(long, value_parser = parse_intervals, conflicts_with = "resume")]
    pub stage_intervals: Option<[f64; 2]>,
    /// Which weights the run trains (`train_only`): `all`; `upsampling`, the cascade's
    /// learnt upsampling selectors alone (every other weight and batch-norm statistic stays as
    /// --init loaded it; a cheap step, the frozen stages need no backward pass); or `coarse`,
    /// the cascade's coarse stage alone (its stride-8 features and regulariser, trained by its
    /// own loss: a step runs no refinement stage; validation still scores the whole network);
    /// or `mid`, the half-resolution stage's regulariser alone (the whole network runs); or
    /// `fine`, the full-resolution stage's regulariser and the stride-2 projection it reads.
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub train_only: Option<PartsArg>,
    /// Stop after this many epochs of this invocation (the run continues with --resume).
    #[arg(long)]
    pub stop_after: Option<usize>,
    /// Train a matching-cost network for SGM instead of a depth network:
    /// `mccnn`, MC-CNN-fast's siamese tower with its hinge loss on patch pairs drawn
    /// through the rig at the ground truth's sphere and a wrong one (`--steps` steps of
    /// `--batch` pairs, Adam at --lr; train frames by --train-frames, validation pairs from
    /// --val-frames); `sweepnet`, the SweepNet-style head on the warped images' window
    /// features, with a softmin cross-entropy over all spheres (`--batch` pixels per step).
    /// Also recognised with --resume.
    #[arg(long, value_enum)]
    pub cost: Option<CostNet>,
    /// Matching-cost training: total steps (default 2000; with --resume, raises the total).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Matching-cost training: sample pairs per step.
    #[arg(long, default_value_t = 128)]
    pub batch: usize,
    /// Compute backend (see the README): cpu (burn flex), libtorch, `libtorch-cuda[:N]`,
    /// `wgpu[:N]`, vulkan or wgpu-cpu; all but cpu need a build with the `libtorch` or `wgpu`
    /// Cargo feature. A new run defaults to cpu; --resume defaults to the backend the run last
    /// ran on (its `backend.txt`).
    #[arg(long, value_parser = parse_backend)]
    pub backend: Option<Backend>,
}

/// The file of a run folder that names the backend the run last ran on; `--resume` without
/// `--backend` continues there (a run started on a GPU is not silently continued on the CPU).
const BACKEND_FILE: &str = "backend.txt";

/// The backend of this invocation: `--backend`, else with --resume the run's recorded one
/// (runs from before it was recorded: cpu), else cpu.
fn backend_of(args: &Args) -> Result<Backend> {
    if let Some(backend) = args.backend {
        return Ok(backend);
    }
    match &args.resume {
        Some(dir) => backend_of_run(dir),
        None => Ok(Backend::Cpu),
    }
}

/// The backend the run in `dir` last ran on: its `backend.txt`, else cpu (a new run, or one
/// from before it was recorded).
///
/// # Errors
/// A `backend.txt` that cannot be read or names no backend.
pub fn backend_of_run(dir: &Path) -> Result<Backend> {
    let path = dir.join(BACKEND_FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Backend::Cpu),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    text.trim().parse::<Backend>().map_err(|e| {
        anyhow!(
            "{}: field `backend`: expected a backend name (cpu, libtorch, libtorch-cuda[:N], \
             wgpu[:N], vulkan, wgpu-cpu): {e}",
            path.display()
        )
    })
}

/// Records `backend` as the one the run in `run_dir` last ran on.
pub fn record_backend(run_dir: &Path, backend: Backend) -> Result<()> {
    let path = run_dir.join(BACKEND_FILE);
    write_atomic(&path, format!("{backend}\n").as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

/// `--cost` values of `train`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CostNet {
    /// The MC-CNN-fast style siamese network.
    Mccnn,
    /// The SweepNet-style network on the warped images.
    Sweepnet,
}

/// Whether `dir` holds a matching-cost run.
fn is_cost_run(dir: &std::path::Path) -> bool {
    std::fs::read_to_string(dir.join("train_config.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<CostTrainConfig>(&t).ok())
        .is_some()
}

/// Whether `dir` holds a SweepNet run.
fn is_sweep_run(dir: &std::path::Path) -> bool {
    std::fs::read_to_string(dir.join("train_config.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<SweepTrainConfig>(&t).ok())
        .is_some()
}

fn train_sweepnet(args: &Args, backend: Backend, device: &Device) -> Result<()> {
    let mut trainer = match &args.resume {
        Some(dir) => SweepTrainer::resume(dir, args.steps, device)
            .with_context(|| format!("resuming {}", dir.display()))?,
        None => {
            let Some(out) = &args.out else {
                bail!("--out RUN_DIR is required for a new run");
            };
            let mut config = SweepTrainConfig {
                data: args.data.clone(),
                steps: args.steps.unwrap_or(3000),
                batch: args.batch,
                lr: args.lr,
                seed: args.seed,
                ..SweepTrainConfig::default()
            };
            if let Some(r) = &args.train_frames {
                config.train_frames = (r.start, r.end);
            }
            if let Some(r) = &args.val_frames {
                config.val_frames = (r.start, r.end);
            }
            SweepTrainer::create(config, out, device)
                .with_context(|| format!("creating {}", out.display()))?
        }
    };
    record_backend(trainer.run_dir(), backend)?;
    outln!(
        "SweepNet cost on {backend}: {} steps of {} pixels x {} spheres from step {} into {}",
        trainer.config.steps,
        trainer.config.batch,
        trainer.config.grid.2,
        trainer.step(),
        trainer.run_dir().display()
    );
    trainer.run(args.stop_after, |r| {
        outln!(
            "step {:5}  train loss {:.4} within-1 {:.3}  val loss {:.4} within-1 {:.3} (ZNCC {:.3})  {:.0} s",
            r.step,
            r.train_loss,
            r.train_acc,
            r.val_loss,
            r.val_acc,
            r.val_zncc_acc,
            r.seconds
        );
    })?;
    Ok(())
}

fn train_cost(args: &Args, backend: Backend, device: &Device) -> Result<()> {
    let mut trainer = match &args.resume {
        Some(dir) => CostTrainer::resume(dir, args.steps, device)
            .with_context(|| format!("resuming {}", dir.display()))?,
        None => {
            let Some(out) = &args.out else {
                bail!("--out RUN_DIR is required for a new run");
            };
            let mut config = CostTrainConfig {
                data: args.data.clone(),
                steps: args.steps.unwrap_or(2000),
                batch: args.batch,
                lr: args.lr,
                seed: args.seed,
                ..CostTrainConfig::default()
            };
            if let Some(r) = &args.train_frames {
                config.train_frames = (r.start, r.end);
            }
            if let Some(r) = &args.val_frames {
                config.val_frames = (r.start, r.end);
            }
            CostTrainer::create(config, out, device)
                .with_context(|| format!("creating {}", out.display()))?
        }
    };
    record_backend(trainer.run_dir(), backend)?;
    outln!(
        "matching-cost network on {backend}: {} steps of {} pairs from step {} into {}",
        trainer.config.steps,
        trainer.config.batch,
        trainer.step(),
        trainer.run_dir().display()
    );
    trainer.run(args.stop_after, |r| {
        outln!(
            "step {:5}  train loss {:.4} acc {:.3}  val loss {:.4} acc {:.3}  {:.0} s",
            r.step,
            r.train_loss,
            r.train_acc,
            r.val_loss,
            r.val_acc,
            r.seconds
        );
    })?;
    Ok(())
}

fn val_text(loss: Option<f64>, metrics: Option<Metrics>, reference: Option<Metrics>) -> String {
    let reference = match reference {
        Some(m) => format!(
            "  | reference (no sky) >1 {:.2}%  >5 {:.2}%  MAE {:.3}",
            m.over1_pct, m.over5_pct, m.mae
        ),
        None => String::new(),
    };
    match (loss, metrics) {
        (Some(loss), Some(m)) => format!(
            "val loss {loss:.3}  >1 {:.2}%  >3 {:.2}%  >5 {:.2}%  MAE {:.3}  RMS {:.3}{reference}",
            m.over1_pct, m.over3_pct, m.over5_pct, m.mae, m.rms
        ),
        _ => "no validation frames".into(),
    }
}

fn print_epoch(r: &EpochRecord) {
    let val = val_text(r.val_loss, r.val, r.val_reference);
    outln!(
        "epoch {:3}  lr {:.0e}  train loss {:.3}  {} steps  {:.3} steps/s (loader wait {:.1} s)  {val}",
        r.epoch,
        r.lr,
        r.train_loss,
        r.steps,
        r.steps_per_second,
        r.loader_wait_seconds
    );
}

/// `on` or `off`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    /// On.
    On,
    /// Off.
    Off,
}

/// `--optimizer` values.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum OptimizerArg {
    /// SGD with momentum.
    Sgd,
    /// Adam.
    Adam,
}

/// `--select-by`: the protocol whose validation MAE picks the best epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SelectArg {
    /// Sky scored as index 0.
    WithSky,
    /// The reference's protocol (sky not scored).
    Reference,
}

/// `--convex-upsampling`: which grids get learnt upsampling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum UpsamplingArg {
    /// Neither: bilinear.
    Off,
    /// The half-resolution grid only.
    Half,
    /// Both refinement grids.
    On,
}

/// `--train-only`: the weights a run trains.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PartsArg {
    /// Every weight.
    All,
    /// The cascade's learnt upsampling selectors.
    Upsampling,
    /// The cascade's coarse stage (stride-8 features and coarse regulariser).
    Coarse,
    /// The cascade's half-resolution stage (its regulariser).
    Mid,
    /// The cascade's full-resolution stage (its regulariser and the stride-2 projection).
    Fine,
}

/// `HALF,FULL`: two values of `T`, each of which `ok` accepts; else the message `expected`
/// (with the text given).
fn parse_pair<T: std::str::FromStr + Copy>(
    text: &str,
    ok: impl Fn(T) -> bool,
    expected: &str,
) -> Result<[T; 2], String>
where
    T::Err: std::fmt::Display,
{
    let values: Vec<T> = text
        .split(',')
        .map(|v| v.trim().parse::<T>().map_err(|e| format!("{v:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match values[..] {
        [half, full] if ok(half) && ok(full) => Ok([half, full]),
        _ => Err(format!("expected HALF,FULL, {expected}, got {text:?}")),
    }
}

/// `--stage-intervals HALF,FULL`: two positive finite spacings.
fn parse_intervals(text: &str) -> Result<[f64; 2], String> {
    parse_pair(
        text,
        |v: f64| v.is_finite() && v > 0.0,
        "two positive index spacings (e.g. 2.5,1.5)",
    )
}

pub fn run(args: &Args) -> Result<()> {
    let backend = backend_of(args)?;
    let device = backend.device()?;
    if args.cost == Some(CostNet::Sweepnet) || args.resume.as_deref().is_some_and(is_sweep_run) {
        return train_sweepnet(args, backend, &device);
    }
    if args.cost.is_some() || args.resume.as_deref().is_some_and(is_cost_run) {
        return train_cost(args, backend, &device);
    }
    let family = match &args.resume {
        Some(dir) => {
            read_run_config(dir)
                .with_context(|| format!("resuming {}", dir.display()))?
                .net
                .family
        }
        None => args.preset.config().family,
    };
    match family {
        Family::OmniMvs => train::<OmniMvsNet>(args, backend, &device),
        Family::Cascade => train::<CascadeNet>(args, backend, &device),
    }
}

fn train<M: Trainable>(args: &Args, backend: Backend, device: &Device) -> Result<()> {
    let mut trainer = match &args.resume {
        Some(dir) => resume_trainer::<M>(args, dir, device)?,
        None => {
            let Some(out) = &args.out else {
                bail!("--out RUN_DIR is required for a new run");
            };
            let config = train_config(args, net_config(args)?);
            Trainer::<M>::create(config, out, device)
                .with_context(|| format!("starting a run in {}", out.display()))?
        }
    };
    record_backend(&trainer.run_dir, backend)?;
    print_run(&trainer, backend);
    run_epochs(&mut trainer, args.stop_after)
}

/// The run in `dir` resumed, with the options that may change on the way (the column window,
/// loader threads, photometric augmentation) applied.
fn resume_trainer<M: Trainable>(args: &Args, dir: &Path, device: &Device) -> Result<Trainer<M>> {
    let mut trainer = Trainer::<M>::resume(dir, args.epochs, device)
        .with_context(|| format!("resuming {}", dir.display()))?;
    if args.column_window.is_some() {
        trainer.set_column_window(args.column_window)?;
    }
    if let Some(threads) = args.loader_threads {
        trainer.set_loader_threads(threads)?;
    }
    match args.photometric {
        // Keep the ranges of a run that has them.
        Some(Switch::On) if trainer.config.photometric.is_none() => {
            trainer.set_photometric(Some(PhotometricAugment::default()))?;
        }
        Some(Switch::Off) => trainer.set_photometric(None)?,
        _ => {}
    }
    Ok(trainer)
}

/// The network of a new run: the preset's, with the cascade options given.
fn net_config(args: &Args) -> Result<NetConfig> {
    let mut net = args.preset.config();
    if args.context_pairs.is_some()
        || args.stage_gates.is_some()
        || args.zncc_cue.is_some()
        || args.coarse_distribution.is_some()
        || args.refine_distribution.is_some()
        || args.sky_weight.is_some()
        || args.convex_upsampling.is_some()
        || args.stage_intervals.is_some()
        || args.coarse_feature_channels.is_some()
        || args.coarse_cue_oversample.is_some()
        || args.coarse_cue_depths.is_some()
        || args.coarse_spheres.is_some()
        || args.coarse_cue_sgm.is_some()
    {
        if net.family != Family::Cascade {
            bail!(
                "--context-pairs, --stage-gates, --zncc-cue, --coarse-distribution, \
                 --refine-distribution, --sky-weight, --convex-upsampling, \
                 --stage-intervals, --coarse-feature-channels, \
                 --coarse-spheres, \
                 --coarse-cue-oversample, --coarse-cue-depths and --coarse-cue-sgm are \
                 options of --preset cascade"
            );
        }
        if let Some(up) = args.convex_upsampling {
            net.cascade.convex_upsampling = up != UpsamplingArg::Off;
            net.cascade.convex_upsampling_full = up == UpsamplingArg::On;
        }
        if let Some(weight) = args.coarse_distribution {
            net.cascade.coarse_distribution_weight = weight;
        }
        if let Some(weight) = args.refine_distribution {
            net.cascade.refine_distribution_weight = weight;
        }
        if let Some(weight) = args.sky_weight {
            net.cascade.sky_loss_weight = weight;
        }
        if let Some(intervals) = args.stage_intervals {
            net.cascade.stage_intervals = intervals;
        }
        if let Some(factor) = args.coarse_cue_oversample {
            net.cascade.coarse_cue_oversample = factor;
        }
        if let Some(depths) = args.coarse_cue_depths {
            net.cascade.coarse_cue_depths = depths;
        }
        if let Some(spheres) = args.coarse_spheres {
            net.cascade.coarse_spheres = spheres;
        }
        if let Some(sgm) = args.coarse_cue_sgm {
            net.cascade.coarse_cue_sgm = sgm == Switch::On;
        }
        if let Some(channels) = args.coarse_feature_channels {
            net.cascade.feature_channels[2] = channels;
        }
        if let Some(pairs) = args.context_pairs {
            net.cascade.context_pairs = pairs;
        }
        if let Some(gates) = args.stage_gates {
            net.cascade.stage_gates = gates == Switch::On;
        }
        if let Some(cue) = args.zncc_cue {
            net.cascade.zncc_cue = cue == Switch::On;
        }
    }
    Ok(net)
}

/// The training configuration of a new run of network `net`.
fn train_config(args: &Args, net: NetConfig) -> TrainConfig {
    TrainConfig {
        net,
        data: args.data.clone(),
        train_frames: args.train_frames.map(|f| (f.start, f.end)),
        val_frames: args.val_frames.map(|f| (f.start, f.end)),
        epochs: args.epochs.unwrap_or(30),
        lr: args.lr,
        lr_low: args.lr_low.unwrap_or(args.lr / 10.0),
        low_lr_epochs: args.low_lr_epochs,
        optimizer: match args.optimizer {
            OptimizerArg::Sgd => Optimizer::Sgd,
            OptimizerArg::Adam => Optimizer::Adam,
        },
        momentum: args.momentum,
        seed: args.seed,
        rotations: args.rotations,
        max_rotation_deg: args.max_rotation_deg,
        permute_cameras: !args.no_permute,
        max_steps_per_epoch: args.max_steps,
        max_val_frames: args.max_val_frames,
        loader_threads: args.loader_threads.unwrap_or(1),
        init: args.init.clone(),
        column_window: args.column_window,
        photometric: (args.photometric == Some(Switch::On)).then(PhotometricAugment::default),
        frozen_norm_stats: args.frozen_norm_stats == Some(Switch::On),
        select_by: match args.select_by {
            Some(SelectArg::Reference) => Selection::Reference,
            Some(SelectArg::WithSky) | None => Selection::WithSky,
        },
        train_only: match args.train_only {
            Some(PartsArg::Upsampling) => TrainParts::Upsampling,
            Some(PartsArg::Coarse) => TrainParts::Coarse,
            Some(PartsArg::Mid) => TrainParts::Mid,
            Some(PartsArg::Fine) => TrainParts::Fine,
            Some(PartsArg::All) | None => TrainParts::All,
        },
        ..TrainConfig::default()
    }
}

/// Prints what the run trains on and how.
pub fn print_run<M: Trainable>(trainer: &Trainer<M>, backend: Backend) {
    let config = trainer.config.clone();
    let (train, val): (usize, usize) = trainer
        .splits
        .iter()
        .fold((0, 0), |acc, (t, v)| (acc.0 + t.len(), acc.1 + v.len()));
    outln!(
        "{} on {backend}: {} training and {} validation frames from {} dataset(s); epochs {}..{} of {}; \
         {} rotations up to {} deg; camera permutation {}; photometric augmentation {}{}{}",
        trainer.run_dir.display(),
        train,
        val,
        config.data.len(),
        trainer.state.epochs_done + 1,
        config.epochs,
        config.epochs,
        config.rotations,
        config.max_rotation_deg,
        if config.permute_cameras { "on" } else { "off" },
        if config.photometric.is_some() {
            "on"
        } else {
            "off"
        },
        if config.frozen_norm_stats {
            "; batch-norm statistics frozen"
        } else {
            ""
        },
        match config.select_by {
            Selection::WithSky => "",
            Selection::Reference => "; best epoch by the reference protocol's MAE",
        }
    );
}

/// Trains the epochs left (or `stop_after` of them) with a progress bar, printing every
/// epoch's figures and, at the end, where the weights are.
pub fn run_epochs<M: Trainable>(trainer: &mut Trainer<M>, stop_after: Option<usize>) -> Result<()> {
    let config = trainer.config.clone();
    let last = match stop_after {
        Some(n) => (trainer.state.epochs_done + n).min(config.epochs),
        None => config.epochs,
    };
    let bar = ProgressBar::new(0);
    bar.set_style(ProgressStyle::with_template(
        "epoch {prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} steps, {per_sec}, loss {msg}",
    )?);
    let started = Instant::now();
    let mut ema: Option<f64> = None;
    let mut on_step = |s: &StepInfo| {
        if s.step == 0 {
            bar.reset();
            bar.set_length(s.steps as u64);
            bar.set_prefix(format!("{}/{}", s.epoch + 1, config.epochs));
            ema = None;
        }
        let loss = f64::from(s.loss);
        let smooth = ema.map_or(loss, |e| 0.9 * e + 0.1 * loss);
        ema = Some(smooth);
        bar.set_message(format!("{loss:.3} (avg {smooth:.3})"));
        bar.inc(1);
    };
    if let Some(start) = trainer.validate_start()? {
        bar.suspend(|| {
            outln!(
                "start (--init weights, before any step)  {}",
                val_text(start.val_loss, start.val, start.val_reference)
            )
        });
    }
    while trainer.state.epochs_done < last {
        let record = trainer.train_epoch(&mut on_step)?;
        bar.suspend(|| print_epoch(&record));
    }
    bar.finish_and_clear();
    outln!(
        "{} epoch(s) in {:.1} s; weights {}; best {}",
        trainer.state.epochs_done,
        started.elapsed().as_secs_f64(),
        if trainer.state.epochs_done == 0 {
            "none yet".to_string()
        } else {
            trainer
                .run_dir
                .join("model.safetensors")
                .display()
                .to_string()
        },
        match trainer.state.best {
            Some((0, mae)) => format!(
                "the --init weights (val MAE{} {mae:.3}; no epoch beat them): best.safetensors",
                protocol_note(config.select_by)
            ),
            Some((epoch, mae)) => format!(
                "epoch {epoch} (val MAE{} {mae:.3}): best.safetensors",
                protocol_note(config.select_by)
            ),
            None => "none (no validation frames)".into(),
        }
    );
    Ok(())
}

/// How the final line names the MAE that picked the best epoch.
fn protocol_note(selection: Selection) -> &'static str {
    match selection {
        Selection::WithSky => "",
        Selection::Reference => ", reference protocol,",
    }
}
