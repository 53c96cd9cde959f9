//! Epochs over the training frames of one or more datasets, validation, the metrics log, the
//! curves and the checkpoints of a run folder:
//!
//! ```text
//! RUN_DIR/train_config.json        the TrainConfig (read back by resume)
//! RUN_DIR/metrics.jsonl            one EpochRecord per line
//! RUN_DIR/curves.png               training and validation loss per epoch
//! RUN_DIR/model.safetensors+.json  weights after the last finished epoch
//! RUN_DIR/best.safetensors+.json   weights of the epoch with the lowest validation MAE (with
//!                                  --init: the initial weights until an epoch beats them)
//! RUN_DIR/start.json               validation of the --init weights before the first step
//! RUN_DIR/latest.json              which checkpoint to resume from
//! RUN_DIR/checkpoints/epoch-EEEE/  model.bpk, optim.bpk, state.json
//! RUN_DIR/backend.txt              the compute backend the run last ran on (written by
//!                                  `omnimvs train`; `--resume` continues on it)
//! ```
//!
//! Every file is written atomically (`omnimvs_core::fs::write_atomic`: a temporary file, then
//! a rename; a checkpoint is a new folder renamed into place), so killing the process at any
//! moment leaves the previous epoch's checkpoint usable: at most one epoch is lost.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use burn::tensor::{Device, Tensor};
use omnimvs_eval::metrics::{Metrics, Protocol, frame_metrics, mean_metrics, protocol_metrics};
use omnimvs_net::cascade::ColumnWindow;
use omnimvs_net::model::OmniMvsNet;
use omnimvs_sweep::SweepSpec;
use serde::{Deserialize, Serialize};

use crate::augment::RotationSet;
use crate::config::{Selection, TrainConfig};
use crate::error::TrainError;
use crate::learner::Learner;
use crate::loader::{Loader, PlanItem};
use crate::loss::target_data;
use crate::photometric::PhotometricAugment;
use crate::plot::plot_curves;
use crate::record::EpochRecord;
use crate::rng::SplitMix64;
use crate::sample::SampleSource;
use crate::trainable::Trainable;

/// Progress of one training step.
#[derive(Clone, Copy, Debug)]
pub struct StepInfo {
    /// Epoch, 0-based.
    pub epoch: usize,
    /// Step within the epoch, 0-based.
    pub step: usize,
    /// Steps of the epoch.
    pub steps: usize,
    /// Loss of the step (mean absolute index error over valid pixels).
    pub loss: f32,
    /// Learning rate.
    pub lr: f64,
}

/// What a checkpoint records besides the tensors.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    /// Epochs finished.
    pub epochs_done: usize,
    /// Every finished epoch.
    pub history: Vec<EpochRecord>,
    /// Epoch (1-based) with the lowest validation MAE so far and that MAE; epoch 0 is the
    /// `--init` weights, validated before the first step.
    pub best: Option<(usize, f64)>,
    /// Validation of the `--init` weights before the first step (runs started from weights).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<StartRecord>,
}

/// What [`Trainer::validate`] measures on the validation frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Validation {
    /// Mean validation loss (index units), if there are validation frames.
    pub loss: Option<f64>,
    /// The paper's metrics, sky scored as index 0 (what training asks for).
    pub with_sky: Option<Metrics>,
    /// The reference's protocol (sky not scored; `None` when no frame has a pixel it scores).
    pub reference: Option<Metrics>,
}

impl Validation {
    /// The metrics of the protocol that picks the best epoch.
    pub fn selected(&self, selection: Selection) -> Option<Metrics> {
        match selection {
            Selection::WithSky => self.with_sky,
            Selection::Reference => self.reference,
        }
    }
}

/// Validation of the weights a fine-tuning run starts from (`start.json`), so that its epochs
/// are compared with where they began and `best` only moves when training helped.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StartRecord {
    /// Mean validation loss (index units).
    pub val_loss: Option<f64>,
    /// The paper's metrics on the validation frames (sky scored as index 0, as trained).
    pub val: Option<Metrics>,
    /// The same frames under the reference's protocol (sky not scored; absent in older runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub val_reference: Option<Metrics>,
    /// Wall time of the validation, seconds.
    pub val_seconds: f64,
}

#[derive(Serialize, Deserialize)]
struct Latest {
    checkpoint: PathBuf,
    epochs_done: usize,
}

fn io_error(path: &Path, source: std::io::Error) -> TrainError {
    TrainError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `bytes` to `path` through a synced temporary file and a rename.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), TrainError> {
    omnimvs_core::fs::write_atomic(path, bytes).map_err(|e| io_error(path, e))
}

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), TrainError> {
    let text = serde_json::to_string_pretty(value).map_err(|source| TrainError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    write_atomic(path, (text + "\n").as_bytes())
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, TrainError> {
    let text = std::fs::read_to_string(path).map_err(|e| io_error(path, e))?;
    serde_json::from_str(&text).map_err(|source| TrainError::Json {
        path: path.to_path_buf(),
        source,
    })
}

/// Saves weights (safetensors + JSON) under `name` in `dir`, each file atomically.
fn export_weights<M: Trainable>(
    learner: &Learner<M>,
    dir: &Path,
    name: &str,
) -> Result<(), TrainError> {
    learner
        .net
        .save_weights(&dir.join(format!("{name}.safetensors")))
}

/// A training run on dataset folders, of the paper's network or another [`Trainable`]
/// family.
pub struct Trainer<M: Trainable = OmniMvsNet> {
    /// The run's configuration.
    pub config: TrainConfig,
    /// The run folder.
    pub run_dir: PathBuf,
    /// Model and optimiser.
    pub learner: Learner<M>,
    /// The datasets.
    pub sources: Arc<Vec<SampleSource>>,
    /// `(train, validation)` frames of every source.
    pub splits: Vec<(Vec<u32>, Vec<u32>)>,
    /// Progress of the run.
    pub state: RunState,
    /// Geometry of every `(source, rotation)` used so far, on the training device.
    geometries: HashMap<(usize, usize), M::Geometry>,
    /// Geometry of every source's identity rotation on the inference device.
    val_geometries: HashMap<usize, M::Geometry>,
}

/// Reads the configuration of the run in `run_dir` (to choose the network family before
/// resuming it).
///
/// # Errors
/// [`TrainError`] when `train_config.json` cannot be read.
pub fn read_run_config(run_dir: &Path) -> Result<TrainConfig, TrainError> {
    read_json(&run_dir.join("train_config.json"))
}

impl<M: Trainable> Trainer<M> {
    /// Starts a new run in `run_dir`, writing `train_config.json`.
    ///
    /// # Errors
    /// [`TrainError`] for an invalid configuration, unreadable data, no training frame, or a
    /// run folder that already holds a run.
    pub fn create(
        config: TrainConfig,
        run_dir: &Path,
        device: &Device,
    ) -> Result<Self, TrainError> {
        let config_path = run_dir.join("train_config.json");
        if config_path.exists() {
            return Err(TrainError::InvalidConfig {
                field: "out",
                message: format!(
                    "{} already holds a run; resume it or choose another folder",
                    run_dir.display()
                ),
            });
        }
        let trainer = Self::build(config, run_dir, device)?;
        write_json(&config_path, &trainer.config)?;
        Ok(trainer)
    }

    /// Resumes the run in `run_dir` from its latest checkpoint; `epochs` replaces the total
    /// number of epochs when given (the schedule follows the new total).
    ///
    /// # Errors
    /// [`TrainError`] when the run folder or its checkpoint cannot be read.
    pub fn resume(
        run_dir: &Path,
        epochs: Option<usize>,
        device: &Device,
    ) -> Result<Self, TrainError> {
        let config: TrainConfig = read_json(&run_dir.join("train_config.json"))?;
        let mut trainer = Self::build(config, run_dir, device)?;
        // A new number of epochs is checked before it is written: a refused one leaves the
        // run's configuration as it was.
        if let Some(epochs) = epochs {
            trainer.update_config(|config| config.epochs = epochs)?;
        }
        let latest_path = run_dir.join("latest.json");
        if latest_path.exists() {
            let latest: Latest = read_json(&latest_path)?;
            let dir = run_dir.join(&latest.checkpoint);
            trainer.learner.load_checkpoint(&dir)?;
            trainer.state = read_json(&dir.join("state.json"))?;
        }
        Ok(trainer)
    }

    fn build(config: TrainConfig, run_dir: &Path, device: &Device) -> Result<Self, TrainError> {
        config.validate()?;
        if config.data.is_empty() {
            return Err(TrainError::InvalidConfig {
                field: "data",
                message: "needs at least one dataset folder".into(),
            });
        }
        let rotations = RotationSet::new(config.rotations, config.max_rotation_deg, config.seed);
        let sources = config
            .data
            .iter()
            .map(|path| SampleSource::open(path, &config.net, rotations.clone()))
            .collect::<Result<Vec<_>, _>>()?;
        let splits: Vec<_> = sources
            .iter()
            .map(|s| config.split(&s.frames_with_gt()))
            .collect();
        if splits.iter().all(|(train, _)| train.is_empty()) {
            return Err(TrainError::InvalidConfig {
                field: "train_frames",
                message: "no training frame with ground truth in the datasets".into(),
            });
        }
        let learner = Learner::for_model(&config, device)?;
        // Only now, when the data and the --init weights have been read: a run that cannot
        // start leaves no empty folder behind.
        std::fs::create_dir_all(run_dir).map_err(|e| io_error(run_dir, e))?;
        Ok(Self {
            config,
            run_dir: run_dir.to_path_buf(),
            learner,
            sources: Arc::new(sources),
            splits,
            state: RunState::default(),
            geometries: HashMap::new(),
            val_geometries: HashMap::new(),
        })
    }

    /// The samples of `epoch` in order: a shuffle of every training frame with a random
    /// rotation and camera shift, from the `(seed, epoch)` stream.
    pub fn plan(&self, epoch: usize) -> Vec<PlanItem> {
        let mut rng = SplitMix64::for_epoch(self.config.seed, epoch);
        let mut items: Vec<(usize, u32)> = self
            .splits
            .iter()
            .enumerate()
            .flat_map(|(s, (train, _))| train.iter().map(move |&f| (s, f)))
            .collect();
        rng.shuffle(&mut items);
        if let Some(max) = self.config.max_steps_per_epoch {
            items.truncate(max);
        }
        items
            .into_iter()
            .map(|(source, frame)| PlanItem {
                source,
                frame,
                rotation: rng.below(self.config.rotations),
                shift: if self.config.permute_cameras {
                    // Each set's own rig: the cascade trains on sets of any camera count.
                    rng.below(self.sources[source].dataset.rig.len())
                } else {
                    0
                },
                // Drawn only with a window, so that runs without one keep their plans.
                window_start: match self.config.column_window {
                    Some(w) => 2 * rng.below((self.config.net.out_width - w) / 2 + 1),
                    None => 0,
                },
                // Likewise drawn only with the augmentation.
                photometric_seed: match self.config.photometric {
                    Some(_) => rng.next_u64(),
                    None => 0,
                },
            })
            .collect()
    }

    fn geometry_for(&mut self, source: usize, rotation: usize) -> Result<M::Geometry, TrainError> {
        if let Some(g) = self.geometries.get(&(source, rotation)) {
            return Ok(g.clone());
        }
        let g = self
            .learner
            .net
            .geometry(&self.sources[source], rotation, &self.learner.device)?;
        self.geometries.insert((source, rotation), g.clone());
        Ok(g)
    }

    /// Changes the run's configuration from now on: the changed copy is validated and
    /// written to `train_config.json` before it replaces the current one, so a change the
    /// run cannot use, or cannot record, leaves both as they were.
    fn update_config(&mut self, change: impl FnOnce(&mut TrainConfig)) -> Result<(), TrainError> {
        let mut config = self.config.clone();
        change(&mut config);
        config.validate()?;
        write_json(&self.run_dir.join("train_config.json"), &config)?;
        self.config = config;
        Ok(())
    }

    /// Sets the number of loader threads from now on (a resumed run may move to a machine
    /// with more cores) and records it in `train_config.json`; the samples do not change.
    ///
    /// # Errors
    /// [`TrainError`] for 0 threads or a file that cannot be written.
    pub fn set_loader_threads(&mut self, threads: usize) -> Result<(), TrainError> {
        self.update_config(|config| config.loader_threads = threads)
    }

    /// Sets the training window of longitudes from now on (a resumed run may take one it
    /// did not have) and records it in `train_config.json`.
    ///
    /// # Errors
    /// [`TrainError`] for a window the run cannot use or a file that cannot be written.
    pub fn set_column_window(&mut self, width: Option<usize>) -> Result<(), TrainError> {
        self.update_config(|config| config.column_window = width)
    }

    /// Sets the photometric augmentation from now on (a resumed run may start or stop it) and
    /// records it in `train_config.json`.
    ///
    /// # Errors
    /// [`TrainError`] for ranges the run cannot use or a file that cannot be written.
    pub fn set_photometric(
        &mut self,
        photometric: Option<PhotometricAugment>,
    ) -> Result<(), TrainError> {
        self.update_config(|config| config.photometric = photometric)
    }

    /// Trains until `config.epochs`, validating and checkpointing after every epoch.
    ///
    /// # Errors
    /// [`TrainError`] when a sample cannot be read or a file cannot be written.
    pub fn run(
        &mut self,
        on_step: &mut dyn FnMut(&StepInfo),
        on_epoch: &mut dyn FnMut(&EpochRecord),
    ) -> Result<(), TrainError> {
        self.validate_start()?;
        while self.state.epochs_done < self.config.epochs {
            let record = self.train_epoch(on_step)?;
            on_epoch(&record);
        }
        Ok(())
    }

    /// Validates the `--init` weights of a run that has not finished an epoch yet, once:
    /// records them (`state.start`, `start.json`) and makes them the best so far (epoch 0,
    /// `best.safetensors`), so that an epoch is only kept as best when it beats its start.
    /// Returns the record when it validated now; `None` for a run without `--init`, one past
    /// its first epoch or one validated already.
    ///
    /// # Errors
    /// [`TrainError`] when a frame cannot be read or a file cannot be written.
    pub fn validate_start(&mut self) -> Result<Option<StartRecord>, TrainError> {
        if self.config.init.is_none() || self.state.epochs_done > 0 || self.state.start.is_some() {
            return Ok(None);
        }
        let start = Instant::now();
        let v = self.validate()?;
        let record = StartRecord {
            val_loss: v.loss,
            val: v.with_sky,
            val_reference: v.reference,
            val_seconds: start.elapsed().as_secs_f64(),
        };
        self.state.start = Some(record);
        write_json(&self.run_dir.join("start.json"), &record)?;
        if let Some(m) = v.selected(self.config.select_by) {
            self.state.best = Some((0, m.mae));
            export_weights(&self.learner, &self.run_dir, "best")?;
        }
        Ok(Some(record))
    }

    /// Trains one epoch, validates, writes the log, the curves and a checkpoint.
    ///
    /// # Errors
    /// See [`Trainer::run`].
    pub fn train_epoch(
        &mut self,
        on_step: &mut dyn FnMut(&StepInfo),
    ) -> Result<EpochRecord, TrainError> {
        let epoch = self.state.epochs_done;
        let lr = self.config.lr_at(epoch);
        let plan = self.plan(epoch);
        let steps = plan.len();
        let mut loader = Loader::spawn(
            Arc::clone(&self.sources),
            plan,
            self.config.prefetch,
            self.config.loader_threads,
            self.config.photometric.clone(),
        );
        let (mut loss_sum, mut wait) = (0f64, 0f64);
        let start = Instant::now();
        for step in 0..steps {
            let waited = Instant::now();
            let Some((item, sample)) = loader.next() else {
                break;
            };
            wait += waited.elapsed().as_secs_f64();
            let mut sample = sample?;
            sample.window = self.config.column_window.map(|width| ColumnWindow {
                start: item.window_start,
                width,
            });
            let cams = self.sources[item.source].dataset.rig.len();
            let order: Vec<usize> = (0..cams).map(|j| (j + item.shift) % cams).collect();
            let geometry = self.geometry_for(item.source, item.rotation)?;
            let loss = self.learner.step(&sample, &geometry, &order, lr)?;
            loss_sum += f64::from(loss);
            on_step(&StepInfo {
                epoch,
                step,
                steps,
                loss,
                lr,
            });
        }
        drop(loader);
        let train_seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let v = self.validate()?;
        let record = EpochRecord {
            epoch: epoch + 1,
            lr,
            train_loss: loss_sum / steps.max(1) as f64,
            steps,
            train_seconds,
            steps_per_second: steps as f64 / train_seconds.max(1e-9),
            loader_wait_seconds: wait,
            val_loss: v.loss,
            val: v.with_sky,
            val_reference: v.reference,
            val_seconds: start.elapsed().as_secs_f64(),
        };
        self.state.epochs_done = epoch + 1;
        self.state.history.push(record.clone());
        let selected = v.selected(self.config.select_by);
        let improved = match (selected, self.state.best) {
            (Some(m), Some((_, best))) => m.mae < best,
            (Some(_), None) => true,
            (None, _) => false,
        };
        if improved && let Some(m) = selected {
            self.state.best = Some((epoch + 1, m.mae));
        }
        self.write_outputs(improved)?;
        Ok(record)
    }

    /// Mean loss and metrics on the validation frames (identity rotation and camera order,
    /// inference mode), taken from the sources in turn up to `max_val_frames`, under both
    /// protocols.
    ///
    /// # Errors
    /// [`TrainError`] when a frame cannot be read.
    pub fn validate(&mut self) -> Result<Validation, TrainError> {
        let device = self.learner.device.clone().without_autodiff();
        // On burn flex, validation runs the host path, as `omnimvs infer` does there.
        let host = omnimvs_net::hostconv::pays_on(&device);
        let net = self.learner.inference_net();
        let net = if host { net.on_host() } else { net };
        let c = net.config().clone();
        let mut losses = Vec::new();
        let mut metrics = Vec::new();
        let mut reference = Vec::new();
        // Round-robin over the sources, so that a frame limit still sees every dataset.
        let longest = self.splits.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
        let frames: Vec<(usize, u32)> = (0..longest)
            .flat_map(|k| {
                self.splits
                    .iter()
                    .enumerate()
                    .filter_map(move |(s, (_, val))| val.get(k).map(|&f| (s, f)))
            })
            .take(self.config.max_val_frames.unwrap_or(usize::MAX))
            .collect();
        for (s, frame) in frames {
            let source = &self.sources[s];
            let sample = source.load(s, frame, 0, None)?;
            let images = self.learner.image_tensors_on(&sample, &device);
            let geometry = match self.val_geometries.get(&s) {
                Some(g) => g.clone(),
                None => {
                    let g = net.validation_geometry(source, &device, host)?;
                    self.val_geometries.insert(s, g.clone());
                    g
                }
            };
            let index = net.predict(&images, &geometry, source)?;
            let (target, mask) = target_data(&sample.gt);
            let loss = crate::loss::masked_l1(
                index.clone(),
                Tensor::from_data(target, &device),
                Tensor::from_data(mask, &device),
            )
            .into_scalar::<f32>();
            losses.push(f64::from(loss));
            let index =
                index
                    .into_data()
                    .try_into_vec_as::<f32>()
                    .map_err(|e| TrainError::Shape {
                        what: format!("index map ({e:?})"),
                        expected: vec![],
                        actual: vec![],
                    })?;
            metrics.push(frame_metrics(&index, &sample.gt, c.num_invdepth)?);
            let spec = SweepSpec::new(source.grid, source.hypotheses);
            if let Some(truth) = source.dataset.eval_truth(frame, &spec)?
                && let Ok(m) = protocol_metrics(&index, &truth, c.num_invdepth, Protocol::Reference)
            {
                reference.push(m);
            }
        }
        let loss = (!losses.is_empty()).then(|| losses.iter().sum::<f64>() / losses.len() as f64);
        Ok(Validation {
            loss,
            with_sky: mean_metrics(&metrics),
            reference: mean_metrics(&reference),
        })
    }

    fn write_outputs(&self, improved: bool) -> Result<(), TrainError> {
        let dir = &self.run_dir;
        // Metrics log and curves first: they only describe finished epochs.
        let mut log = String::new();
        for record in &self.state.history {
            let line = serde_json::to_string(record).map_err(|source| TrainError::Json {
                path: dir.join("metrics.jsonl"),
                source,
            })?;
            log.push_str(&line);
            log.push('\n');
        }
        write_atomic(&dir.join("metrics.jsonl"), log.as_bytes())?;
        plot_curves(&self.state.history, &dir.join("curves.png"))?;
        // Checkpoint: a new folder, then the pointer to it, then the old folders go.
        let name = format!("epoch-{:04}", self.state.epochs_done);
        let checkpoints = dir.join("checkpoints");
        let tmp = checkpoints.join(format!("{name}.partial"));
        if tmp.exists() {
            std::fs::remove_dir_all(&tmp).map_err(|e| io_error(&tmp, e))?;
        }
        self.learner.save_checkpoint(&tmp)?;
        write_json(&tmp.join("state.json"), &self.state)?;
        let final_dir = checkpoints.join(&name);
        if final_dir.exists() {
            std::fs::remove_dir_all(&final_dir).map_err(|e| io_error(&final_dir, e))?;
        }
        std::fs::rename(&tmp, &final_dir).map_err(|e| io_error(&final_dir, e))?;
        write_json(
            &dir.join("latest.json"),
            &Latest {
                checkpoint: PathBuf::from("checkpoints").join(&name),
                epochs_done: self.state.epochs_done,
            },
        )?;
        if let Ok(entries) = std::fs::read_dir(&checkpoints) {
            for entry in entries.flatten() {
                if entry.file_name().to_string_lossy() != name {
                    let _ = std::fs::remove_dir_all(entry.path());
                }
            }
        }
        export_weights(&self.learner, dir, "model")?;
        if improved {
            export_weights(&self.learner, dir, "best")?;
        }
        Ok(())
    }
}
