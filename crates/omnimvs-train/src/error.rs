//! Errors of the training crate.

use std::path::PathBuf;

/// Everything that can go wrong preparing, running, checkpointing or resuming a training run.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// A training configuration field has a value the run cannot use.
    #[error("invalid training configuration: `{field}` {message}")]
    InvalidConfig {
        /// The offending field.
        field: &'static str,
        /// What was expected.
        message: String,
    },
    /// A sample, a ground truth or a tensor has the wrong size.
    #[error("shape mismatch for {what}: expected {expected:?}, got {actual:?}")]
    Shape {
        /// Which input.
        what: String,
        /// Expected dimensions.
        expected: Vec<usize>,
        /// Actual dimensions.
        actual: Vec<usize>,
    },
    /// Reading or writing a file of the run failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A checkpoint file (model or optimiser state) could not be written, read or applied.
    #[error("{path}: {message}")]
    Checkpoint {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A file of the run (configuration, state, pointer, log) could not be parsed or written.
    #[error("{path}: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
    /// The training curves could not be drawn.
    #[error("drawing the training curves: {0}")]
    Plot(String),
    /// The network: building it, its weights, a forward pass.
    #[error(transparent)]
    Net(#[from] omnimvs_net::NetError),
    /// Reading the dataset (images, masks, ground truth) failed.
    #[error(transparent)]
    Data(#[from] omnimvs_data::DataError),
    /// Building or reading the lookup table failed.
    #[error(transparent)]
    Sweep(#[from] omnimvs_sweep::SweepError),
}
