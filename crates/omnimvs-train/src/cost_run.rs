//! What the matching-cost trainers (`mccnn`, `sweepnet`) share: the datasets opened for
//! drawing samples through the rig, and the run folder (configuration, metrics lines and a
//! resumable checkpoint, every file written atomically).

use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::module::Module;
use burn::optim::{AdamConfig, GradientsParams, ModuleOptimizer};
use burn::store::{BurnpackStore, ModuleSnapshot};
use burn::tensor::Tensor;
use omnimvs_camera::ValidityMask;
use omnimvs_core::fs::write_atomic;
use omnimvs_data::Dataset;
use omnimvs_sweep::SphereProjector;
use omnimvs_sweep::SweepSpec;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::error::TrainError;
use crate::rng::SplitMix64;

/// A dataset opened for sampling: its masks, the sweep of the ground truth and the fast
/// projectors of that sweep's grid.
pub(crate) struct Source {
    pub dataset: Dataset,
    pub masks: Vec<ValidityMask>,
    pub spec: SweepSpec,
    pub projectors: Vec<SphereProjector>,
}

pub(crate) fn io_err(path: &Path) -> impl Fn(std::io::Error) -> TrainError + '_ {
    move |source| TrainError::Io {
        path: path.to_path_buf(),
        source,
    }
}

pub(crate) fn ckpt_err(path: &Path, e: impl std::fmt::Display) -> TrainError {
    TrainError::Checkpoint {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Opens every dataset of `data` for the grid `(h, w, N)` over +-45 degrees.
pub(crate) fn open_sources(
    data: &[PathBuf],
    (h, w, n): (usize, usize, usize),
) -> Result<Vec<Source>, TrainError> {
    data.iter()
        .map(|path| {
            let dataset = Dataset::open(path)?;
            let masks = dataset.masks()?;
            let spec = dataset.sweep_spec(h, w, 90.0, n)?;
            let projectors = dataset
                .rig
                .cameras
                .iter()
                .enumerate()
                .map(|(i, c)| SphereProjector::new(c, i + 1, &spec.grid))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| TrainError::InvalidConfig {
                    field: "data",
                    message: format!("{}: {e}", path.display()),
                })?;
            Ok(Source {
                dataset,
                masks,
                spec,
                projectors,
            })
        })
        .collect()
}

/// Starts a run in `run_dir` (created) with `config` as `train_config.json`; refused if the
/// folder holds a run already.
pub(crate) fn create_run<C: Serialize>(run_dir: &Path, config: &C) -> Result<(), TrainError> {
    let path = run_dir.join("train_config.json");
    if path.exists() {
        return Err(TrainError::InvalidConfig {
            field: "out",
            message: format!("{} holds a run already (resume it)", run_dir.display()),
        });
    }
    std::fs::create_dir_all(run_dir).map_err(io_err(run_dir))?;
    let json = serde_json::to_string_pretty(config).map_err(|source| TrainError::Json {
        path: path.clone(),
        source,
    })?;
    write_atomic(&path, (json + "\n").as_bytes()).map_err(io_err(&path))
}

/// The `train_config.json` of the run in `run_dir`.
pub(crate) fn read_run_config<C: DeserializeOwned>(run_dir: &Path) -> Result<C, TrainError> {
    let path = run_dir.join("train_config.json");
    let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
    serde_json::from_str(&text).map_err(|source| TrainError::Json { path, source })
}

/// Resumable state, `checkpoint/state.json`.
#[derive(Debug, Serialize, Deserialize)]
struct State {
    step: usize,
}

/// Writes `checkpoint/` (model, Adam state, step) under `run_dir`, each file atomically.
pub(crate) fn save_checkpoint<M: Module>(
    run_dir: &Path,
    net: &M,
    optim: &ModuleOptimizer,
    step: usize,
) -> Result<(), TrainError> {
    let dir = run_dir.join("checkpoint");
    std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
    let model = dir.join("model.bpk");
    let mut store = BurnpackStore::from_bytes(None);
    net.save_into(&mut store).map_err(|e| ckpt_err(&model, e))?;
    let bytes = store.get_bytes().map_err(|e| ckpt_err(&model, e))?;
    write_atomic(&model, &bytes).map_err(io_err(&model))?;
    let optim_path = dir.join("optim.bpk");
    let bytes = optim.into_bytes().map_err(|e| ckpt_err(&optim_path, e))?;
    write_atomic(&optim_path, &bytes).map_err(io_err(&optim_path))?;
    let state = dir.join("state.json");
    let json = serde_json::to_string(&State { step }).unwrap_or_default();
    write_atomic(&state, json.as_bytes()).map_err(io_err(&state))
}

/// The network, Adam state and step of the last checkpoint under `run_dir`; a fresh Adam and
/// step 0 when there is none yet.
pub(crate) fn load_checkpoint<M: Module>(
    run_dir: &Path,
    mut net: M,
) -> Result<(M, ModuleOptimizer, usize), TrainError> {
    let dir = run_dir.join("checkpoint");
    let state_path = dir.join("state.json");
    if !state_path.exists() {
        return Ok((net, AdamConfig::new().init(), 0));
    }
    let text = std::fs::read_to_string(&state_path).map_err(io_err(&state_path))?;
    let state: State = serde_json::from_str(&text).map_err(|source| TrainError::Json {
        path: state_path.clone(),
        source,
    })?;
    let model = dir.join("model.bpk");
    let mut store = BurnpackStore::from_file(&model).auto_extension(false);
    net.load_from(&mut store).map_err(|e| ckpt_err(&model, e))?;
    let optim_path = dir.join("optim.bpk");
    let optim = AdamConfig::new()
        .init()
        .load(&optim_path)
        .map_err(|e| ckpt_err(&optim_path, e))?;
    Ok((net, optim, state.step))
}

/// Appends one line to the run's `metrics.jsonl` (rewritten atomically).
pub(crate) fn append_metrics<R: Serialize>(run_dir: &Path, record: &R) -> Result<(), TrainError> {
    let metrics = run_dir.join("metrics.jsonl");
    let mut text = std::fs::read_to_string(&metrics).unwrap_or_default();
    text.push_str(&serde_json::to_string(record).unwrap_or_default());
    text.push('\n');
    write_atomic(&metrics, text.as_bytes()).map_err(io_err(&metrics))
}

/// When a matching-cost run steps, draws from a new frame and writes a metrics line.
pub(crate) struct Schedule {
    /// The run's seed: frames by `seed` and `step / frame_every`, batches by `seed` and step.
    pub seed: u64,
    /// Total steps.
    pub steps: usize,
    /// Steps on each loaded frame before the next one.
    pub frame_every: usize,
    /// Training frames of each dataset, inclusive.
    pub train_frames: (u32, u32),
    /// Steps between metrics lines and checkpoints.
    pub log_every: usize,
    /// Adam learning rate.
    pub lr: f64,
}

/// The figures of one metrics line: the means over the training steps since the last line and
/// over the validation batches (loss and each trainer's accuracy), the step and the seconds
/// since this invocation started. MC-CNN's metrics line as it is (`mccnn::CostRecord`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Progress {
    pub step: usize,
    pub train_loss: f32,
    /// The trainer's accuracy: MC-CNN's, the share of training pairs where the true sphere
    /// matches better than the wrong one; SweepNet's, the share of pixels whose lowest cost
    /// is within one hypothesis of the truth.
    pub train_acc: f32,
    pub val_loss: f32,
    pub val_acc: f32,
    pub seconds: f64,
}

/// What every matching-cost run holds beside its own configuration: its folder, the network
/// being trained (on the autodiff device), Adam's state, the step and the opened datasets.
pub(crate) struct RunState<M> {
    pub run_dir: PathBuf,
    pub net: M,
    pub optim: ModuleOptimizer,
    pub device: burn::tensor::Device,
    pub step: usize,
    pub sources: Vec<Source>,
}

impl<M: Module> RunState<M> {
    /// A new run: the datasets of `data` opened for the grid and accepted by `check` first,
    /// then `run_dir` created with `config`, then the network built by `build` on the
    /// autodiff device seeded with `seed`.
    #[allow(clippy::too_many_arguments)]
    pub fn create<C: Serialize>(
        run_dir: &Path,
        config: &C,
        data: &[PathBuf],
        grid: (usize, usize, usize),
        seed: u64,
        device: &burn::tensor::Device,
        check: impl FnOnce(&[Source]) -> Result<(), TrainError>,
        build: impl FnOnce(&burn::tensor::Device) -> Result<M, TrainError>,
    ) -> Result<Self, TrainError> {
        let sources = open_sources(data, grid)?;
        check(&sources)?;
        create_run(run_dir, config)?;
        let device = device.clone().autodiff();
        device.seed(seed);
        let net = build(&device)?;
        Ok(Self {
            run_dir: run_dir.to_path_buf(),
            net,
            optim: AdamConfig::new().init(),
            device,
            step: 0,
            sources,
        })
    }

    /// The run in `run_dir` from its last checkpoint (a network of `build`'s shape).
    pub fn resume(
        run_dir: &Path,
        data: &[PathBuf],
        grid: (usize, usize, usize),
        device: &burn::tensor::Device,
        build: impl FnOnce(&burn::tensor::Device) -> Result<M, TrainError>,
    ) -> Result<Self, TrainError> {
        let device = device.clone().autodiff();
        let (net, optim, step) = load_checkpoint(run_dir, build(&device)?)?;
        let sources = open_sources(data, grid)?;
        Ok(Self {
            run_dir: run_dir.to_path_buf(),
            net,
            optim,
            device,
            step,
            sources,
        })
    }

    /// Writes the checkpoint of the current step.
    pub fn save_checkpoint(&self) -> Result<(), TrainError> {
        save_checkpoint(&self.run_dir, &self.net, &self.optim, self.step)
    }

    /// The dataset and frame that the steps from `step` on draw from: a new one every
    /// `frame_every` steps, among the frames `train_frames` of every dataset, chosen by
    /// `seed` and `step / frame_every` (so that a resumed run chooses as the first did).
    pub fn frame_for_step(
        &self,
        seed: u64,
        step: usize,
        frame_every: usize,
        (f0, f1): (u32, u32),
    ) -> (usize, u32) {
        let mut rng = SplitMix64::for_epoch(seed, step / frame_every);
        let source = rng.below(self.sources.len());
        let frame = f0 + rng.below((f1 - f0 + 1) as usize) as u32;
        (source, frame)
    }

    /// One Adam step of the network on `loss` (a scalar of the autodiff device).
    pub fn descend(&mut self, loss: Tensor<1>, lr: f64) {
        let grads = GradientsParams::from_grads(loss.backward(), &self.net);
        self.net = self.optim.step(lr, self.net.clone(), grads);
    }

    /// The matching-cost trainers' loop, up to `schedule.steps` (or `stop_after` more steps):
    /// every step draws a batch (`draw`; `None` when the frame offers none, and the step
    /// passes) from the frame of [`Self::frame_for_step`] (`load`, kept for `frame_every`
    /// steps) with a generator seeded by the step, and descends on its `loss`; every
    /// `log_every` steps and at the end, the network without autodiff is scored on `val` by
    /// the same `loss` and `line` gets the [`Progress`] (to write the metrics line and the
    /// checkpoint). A resumed run draws as the first did.
    #[allow(clippy::too_many_arguments)]
    pub fn train<F, B>(
        &mut self,
        schedule: &Schedule,
        stop_after: Option<usize>,
        val: &[B],
        load: impl Fn(&[Source], usize, u32) -> Result<F, TrainError>,
        draw: impl Fn(&[Source], &F, &mut SplitMix64) -> Option<B>,
        loss: impl Fn(&M, &B, &burn::tensor::Device) -> (Tensor<1>, f32),
        mut line: impl FnMut(&Self, &Progress) -> Result<(), TrainError>,
    ) -> Result<(), TrainError> {
        let end = stop_after.map_or(schedule.steps, |s| (self.step + s).min(schedule.steps));
        let (mut loss_sum, mut acc_sum, mut count) = (0f32, 0f32, 0usize);
        let mut frame: Option<F> = None;
        let t0 = Instant::now();
        while self.step < end {
            let step = self.step;
            let current = match frame.take() {
                Some(loaded) if !step.is_multiple_of(schedule.frame_every) => loaded,
                _ => {
                    let (s, f) = self.frame_for_step(
                        schedule.seed,
                        step,
                        schedule.frame_every,
                        schedule.train_frames,
                    );
                    load(&self.sources, s, f)?
                }
            };
            let mut rng = SplitMix64::for_epoch(schedule.seed ^ 0xA5A5, step);
            if let Some(batch) = draw(&self.sources, &current, &mut rng) {
                let (l, acc) = loss(&self.net, &batch, &self.device);
                loss_sum += l.clone().into_scalar::<f32>();
                acc_sum += acc;
                count += 1;
                self.descend(l, schedule.lr);
            }
            frame = Some(current);
            self.step += 1;
            if self.step.is_multiple_of(schedule.log_every) || self.step == end {
                let inference = self.net.valid();
                let device = self.device.clone().without_autodiff();
                let (mut val_loss, mut val_acc) = (0f32, 0f32);
                for b in val {
                    let (l, a) = loss(&inference, b, &device);
                    val_loss += l.into_scalar::<f32>();
                    val_acc += a;
                }
                let (n, v) = (count.max(1) as f32, val.len().max(1) as f32);
                let progress = Progress {
                    step: self.step,
                    train_loss: loss_sum / n,
                    train_acc: acc_sum / n,
                    val_loss: val_loss / v,
                    val_acc: val_acc / v,
                    seconds: t0.elapsed().as_secs_f64(),
                };
                (loss_sum, acc_sum, count) = (0.0, 0.0, 0);
                line(self, &progress)?;
            }
        }
        Ok(())
    }
}
