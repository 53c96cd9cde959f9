//! The matching-cost networks' one trainer: [`CostModelTrainer`], generic over a
//! [`CostModel`] (what differs between MC-CNN in `mccnn` and SweepNet in `sweepnet`: the
//! network, the frames and batches drawn, the loss, the metrics line, the saved weights). It
//! holds what they share: the datasets opened for drawing samples through the rig, the
//! seeded frame and batch schedule, Adam's steps, validation, and the run folder
//! (configuration, metrics lines and a resumable checkpoint, every file written atomically).

use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::module::Module;
use burn::optim::{AdamConfig, GradientsParams, ModuleOptimizer};
use burn::store::{BurnpackStore, ModuleSnapshot};
use burn::tensor::{Device, Tensor};
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
pub struct Source {
    pub(crate) dataset: Dataset,
    pub(crate) masks: Vec<ValidityMask>,
    pub(crate) spec: SweepSpec,
    pub(crate) projectors: Vec<SphereProjector>,
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
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
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

/// What differs between the matching-cost networks' training, implemented by each one's
/// configuration (`train_config.json`): the network, the frames and batches it draws, its loss
/// and its metrics line. [`CostModelTrainer`] is the rest: the run folder, resuming, the steps,
/// validation, the metrics log and the checkpoints.
pub trait CostModel: Serialize + DeserializeOwned {
    /// The network.
    type Net: Module;
    /// One frame loaded for drawing samples.
    type Frame;
    /// The samples of one step (or one validation batch).
    type Batch;
    /// One line of `metrics.jsonl`.
    type Record: Serialize;

    /// Dataset folders with ground truth.
    fn data(&self) -> &[PathBuf];
    /// Grid and hypotheses of the ground truth (`h`, `w`, `N`).
    fn grid(&self) -> (usize, usize, usize);
    /// Validation frames of each dataset, inclusive.
    fn val_frames(&self) -> (u32, u32);
    /// The steps, frames, seed and learning rate of the run.
    fn schedule(&self) -> Schedule;
    /// Sets the total steps (a resumed run may raise them).
    fn set_steps(&mut self, steps: usize);

    /// Checks the configuration before anything is opened.
    ///
    /// # Errors
    /// [`TrainError::InvalidConfig`] naming what does not fit.
    fn check(&self) -> Result<(), TrainError>;

    /// Checks the opened datasets (the rig the network reads); any by default.
    ///
    /// # Errors
    /// [`TrainError::InvalidConfig`] naming the dataset that does not fit.
    fn check_sources(&self, _sources: &[Source]) -> Result<(), TrainError> {
        Ok(())
    }

    /// A new network on `device`.
    ///
    /// # Errors
    /// The network's own error.
    fn build(&self, device: &Device) -> Result<Self::Net, TrainError>;

    /// Frame `frame` of dataset `source`, ready for drawing samples.
    ///
    /// # Errors
    /// [`TrainError`] for an unreadable frame or one without ground truth.
    fn load_frame(
        &self,
        sources: &[Source],
        source: usize,
        frame: u32,
    ) -> Result<Self::Frame, TrainError>;

    /// One training step's batch from `frame`; `None` when the frame offers none.
    fn draw(
        &self,
        sources: &[Source],
        frame: &Self::Frame,
        rng: &mut SplitMix64,
    ) -> Option<Self::Batch>;

    /// The fixed validation batches of validation frame `j` (0: the first of the range, 1:
    /// the last) of dataset `source`.
    fn validation_batches(
        &self,
        sources: &[Source],
        frame: &Self::Frame,
        source: usize,
        j: usize,
    ) -> Vec<Self::Batch>;

    /// The loss of a batch (a scalar of `device`) and the model's accuracy on it.
    fn loss(&self, net: &Self::Net, batch: &Self::Batch, device: &Device) -> (Tensor<1>, f32);

    /// The metrics line of `progress` (`val`: the validation batches).
    fn record(&self, progress: &Progress, val: &[Self::Batch]) -> Self::Record;

    /// Writes the weights (safetensors + JSON) to `path`.
    ///
    /// # Errors
    /// [`TrainError`] for a file that cannot be written.
    fn save(net: &Self::Net, path: &Path) -> Result<(), TrainError>;
}

/// A matching-cost training run of the network of `C`: its folder, the network being trained
/// (on the autodiff device), Adam's state, the step and the opened datasets.
pub struct CostModelTrainer<C: CostModel> {
    pub config: C,
    run_dir: PathBuf,
    net: C::Net,
    optim: ModuleOptimizer,
    device: Device,
    step: usize,
    sources: Vec<Source>,
}

impl<C: CostModel> CostModelTrainer<C> {
    /// A new run in `run_dir`: the configuration checked, the datasets opened and checked,
    /// then the folder created with `train_config.json` (refused if it holds a run already),
    /// then the network built on the autodiff device seeded with the run's seed.
    ///
    /// # Errors
    /// [`TrainError`] for unreadable datasets, a bad configuration or an existing run.
    pub fn create(config: C, run_dir: &Path, device: &Device) -> Result<Self, TrainError> {
        config.check()?;
        let sources = open_sources(config.data(), config.grid())?;
        config.check_sources(&sources)?;
        create_run(run_dir, &config)?;
        let device = device.clone().autodiff();
        device.seed(config.schedule().seed);
        let net = config.build(&device)?;
        Ok(Self {
            config,
            run_dir: run_dir.to_path_buf(),
            net,
            optim: AdamConfig::new().init(),
            device,
            step: 0,
            sources,
        })
    }

    /// The run in `run_dir` from its last checkpoint; `steps` raises the total.
    ///
    /// # Errors
    /// [`TrainError`] for a missing or unreadable run.
    pub fn resume(
        run_dir: &Path,
        steps: Option<usize>,
        device: &Device,
    ) -> Result<Self, TrainError> {
        let mut config: C = read_run_config(run_dir)?;
        if let Some(s) = steps {
            config.set_steps(s);
        }
        let device = device.clone().autodiff();
        let (net, optim, step) = load_checkpoint(run_dir, config.build(&device)?)?;
        let sources = open_sources(config.data(), config.grid())?;
        Ok(Self {
            config,
            run_dir: run_dir.to_path_buf(),
            net,
            optim,
            device,
            step,
            sources,
        })
    }

    /// The step the run is at.
    pub fn step(&self) -> usize {
        self.step
    }

    /// The run's folder.
    pub fn run_dir(&self) -> &Path {
        &self.run_dir
    }

    /// The trained network, without autodiff.
    pub fn net(&self) -> C::Net {
        self.net.valid()
    }

    /// Fixed validation batches: those of the first and the last frame of each dataset's
    /// validation range.
    fn validation(&self) -> Result<Vec<C::Batch>, TrainError> {
        let mut out = Vec::new();
        let (v0, v1) = self.config.val_frames();
        for s in 0..self.sources.len() {
            for (j, f) in [v0, v1].into_iter().enumerate() {
                let frame = self.config.load_frame(&self.sources, s, f)?;
                out.extend(self.config.validation_batches(&self.sources, &frame, s, j));
            }
        }
        Ok(out)
    }

    /// The dataset and frame that the steps from `step` on draw from: a new one every
    /// `frame_every` steps, among the frames `train_frames` of every dataset, chosen by
    /// `seed` and `step / frame_every` (so that a resumed run chooses as the first did).
    fn frame_for_step(&self, schedule: &Schedule, step: usize) -> (usize, u32) {
        let (f0, f1) = schedule.train_frames;
        let mut rng = SplitMix64::for_epoch(schedule.seed, step / schedule.frame_every);
        let source = rng.below(self.sources.len());
        let frame = f0 + rng.below((f1 - f0 + 1) as usize) as u32;
        (source, frame)
    }

    /// Trains up to the configuration's steps (or `stop_after` more steps): every step draws a
    /// batch from the frame chosen for the step (kept for `frame_every` steps) with a
    /// generator seeded by the step, and takes an Adam step on its loss; every `log_every`
    /// steps and at the end, the network without autodiff is scored on the validation
    /// batches, the metrics line appended, the checkpoint and `model.safetensors` written and
    /// `report` called with the line. A resumed run draws as the first did.
    ///
    /// # Errors
    /// [`TrainError`] for unreadable frames or unwritable files.
    pub fn run(
        &mut self,
        stop_after: Option<usize>,
        mut report: impl FnMut(&C::Record),
    ) -> Result<(), TrainError> {
        let val = self.validation()?;
        let schedule = self.config.schedule();
        let end = stop_after.map_or(schedule.steps, |s| (self.step + s).min(schedule.steps));
        let (mut loss_sum, mut acc_sum, mut count) = (0f32, 0f32, 0usize);
        let mut frame: Option<C::Frame> = None;
        let t0 = Instant::now();
        while self.step < end {
            let step = self.step;
            let current = match frame.take() {
                Some(loaded) if !step.is_multiple_of(schedule.frame_every) => loaded,
                _ => {
                    let (s, f) = self.frame_for_step(&schedule, step);
                    self.config.load_frame(&self.sources, s, f)?
                }
            };
            let mut rng = SplitMix64::for_epoch(schedule.seed ^ 0xA5A5, step);
            if let Some(batch) = self.config.draw(&self.sources, &current, &mut rng) {
                let (l, acc) = self.config.loss(&self.net, &batch, &self.device);
                loss_sum += l.clone().into_scalar::<f32>();
                acc_sum += acc;
                count += 1;
                let grads = GradientsParams::from_grads(l.backward(), &self.net);
                self.net = self.optim.step(schedule.lr, self.net.clone(), grads);
            }
            frame = Some(current);
            self.step += 1;
            if self.step.is_multiple_of(schedule.log_every) || self.step == end {
                let (val_loss, val_acc) = self.score(&val);
                let n = count.max(1) as f32;
                let progress = Progress {
                    step: self.step,
                    train_loss: loss_sum / n,
                    train_acc: acc_sum / n,
                    val_loss,
                    val_acc,
                    seconds: t0.elapsed().as_secs_f64(),
                };
                (loss_sum, acc_sum, count) = (0.0, 0.0, 0);
                let record = self.config.record(&progress, &val);
                append_metrics(&self.run_dir, &record)?;
                save_checkpoint(&self.run_dir, &self.net, &self.optim, self.step)?;
                C::save(&self.net.valid(), &self.run_dir.join("model.safetensors"))?;
                report(&record);
            }
        }
        Ok(())
    }

    /// The mean loss and accuracy of the network without autodiff on `val`.
    fn score(&self, val: &[C::Batch]) -> (f32, f32) {
        let inference = self.net.valid();
        let device = self.device.clone().without_autodiff();
        let (mut val_loss, mut val_acc) = (0f32, 0f32);
        for b in val {
            let (l, a) = self.config.loss(&inference, b, &device);
            val_loss += l.into_scalar::<f32>();
            val_acc += a;
        }
        let v = val.len().max(1) as f32;
        (val_loss / v, val_acc / v)
    }
}
