//! One epoch of a training run as `metrics.jsonl` records it (written by the trainer, drawn by
//! [`crate::plot`]).

use omnimvs_eval::metrics::Metrics;
use serde::{Deserialize, Serialize};

/// One line of `metrics.jsonl`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpochRecord {
    /// Epoch, 1-based (number of epochs finished).
    pub epoch: usize,
    /// Learning rate of the epoch.
    pub lr: f64,
    /// Mean training loss (index units).
    pub train_loss: f64,
    /// Training steps.
    pub steps: usize,
    /// Wall time of the training steps, seconds.
    pub train_seconds: f64,
    /// Training steps per second.
    pub steps_per_second: f64,
    /// Time the steps waited for the loader thread, seconds.
    pub loader_wait_seconds: f64,
    /// Mean validation loss (index units), if there are validation frames.
    pub val_loss: Option<f64>,
    /// The paper's metrics on the validation frames (sky scored as index 0, as trained).
    pub val: Option<Metrics>,
    /// The same frames under the reference's protocol (sky not scored; absent in older runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub val_reference: Option<Metrics>,
    /// Wall time of the validation, seconds.
    pub val_seconds: f64,
}
