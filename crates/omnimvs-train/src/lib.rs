//! End-to-end training of the networks of `omnimvs-net` (ICCV 2019 paper, sections 3.3 and
//! 5.1, and the cascade): one [`Trainer`] for every [`Trainable`] family. The network crate
//! is the library of inference and weights; this crate is what `omnimvs train` needs on top.
//!
//! - [`error`]: [`TrainError`], what can go wrong in a run.
//! - [`config`]: the training configuration written next to every run.
//! - [`rng`]: the seeded generator behind shuffling and augmentation (resumable by epoch).
//! - [`augment`]: the fixed set of small rig rotations and the ground truth rotated to match.
//! - [`photometric`]: per-camera exposure, gamma, vignetting, blur and noise of real cameras.
//! - [`sample`]: reading one training sample (normalised inputs, ground-truth indices).
//! - [`loader`]: a loader thread that prepares samples while the step runs.
//! - [`cost_run`]: the matching-cost networks' one trainer ([`CostModelTrainer`]) over what
//!   differs between them ([`CostModel`]); [`mccnn`] and [`sweepnet`] implement it.
//! - [`trainable`]: what the trainer needs of a network family (the paper's, the cascade).
//! - [`learner`]: the model, the optimiser, the masked L1 loss, one step, checkpoints.
//! - [`trainer`]: epochs over datasets, validation, metrics log, curves, checkpoints.
//! - [`plot`]: the PNG of the training and validation curves.

pub mod augment;
pub mod config;
pub mod cost_run;
pub mod error;
pub mod learner;
pub mod loader;
pub mod loss;
pub mod mccnn;
pub mod photometric;
pub mod plot;
pub mod record;
pub mod rng;
pub mod sample;
pub mod sweepnet;
pub mod trainable;
pub mod trainer;

pub use augment::{RotationSet, resample_ground_truth};
pub use config::{Optimizer, Selection, TrainConfig, TrainParts};
pub use cost_run::{CostModel, CostModelTrainer};
pub use error::TrainError;
pub use learner::Learner;
pub use loss::masked_l1;
pub use photometric::PhotometricAugment;
pub use record::EpochRecord;
pub use sample::{Sample, SampleSource};
pub use trainable::Trainable;
pub use trainer::{StartRecord, StepInfo, Trainer, Validation};
