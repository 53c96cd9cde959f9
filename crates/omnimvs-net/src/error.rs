//! Errors of the network crate.

use std::path::PathBuf;

/// Everything that can go wrong building, loading or running the network.
#[derive(Debug, thiserror::Error)]
pub enum NetError {
    /// A configuration field has a value the network cannot use.
    #[error("invalid network configuration: `{field}` {message}")]
    InvalidConfig {
        /// The offending field.
        field: &'static str,
        /// What was expected.
        message: String,
    },
    /// A preset name that does not exist.
    #[error("unknown network preset `{0}` (expected `paper`, `tiny` or `cascade`)")]
    UnknownPreset(String),
    /// An input tensor or lookup table has the wrong size.
    #[error("shape mismatch for {what}: expected {expected:?}, got {actual:?}")]
    Shape {
        /// Which input.
        what: String,
        /// Expected dimensions.
        expected: Vec<usize>,
        /// Actual dimensions.
        actual: Vec<usize>,
    },
    /// A rig with a number of cameras the network does not run on.
    #[error("{what}: {count} cameras; {supported}")]
    Cameras {
        /// Whose cameras (a rig file, the images of a frame).
        what: String,
        /// How many there are.
        count: usize,
        /// What the network takes, in words.
        supported: String,
    },
    /// A camera order that is not a permutation of the cameras.
    #[error("camera order {order:?} is not a permutation of 0..{num_cameras}")]
    CameraOrder {
        /// The order given.
        order: Vec<usize>,
        /// Number of cameras of the network.
        num_cameras: usize,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A configuration file could not be parsed.
    #[error("{path}: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
    /// Reading the dataset (images, masks, ground truth) failed.
    #[error(transparent)]
    Data(#[from] omnimvs_data::DataError),
    /// Building or reading the lookup table failed.
    #[error(transparent)]
    Sweep(#[from] omnimvs_sweep::SweepError),

    #[error(transparent)]
    Stereo(#[from] omnimvs_stereo::StereoError),
    /// A weight file could not be read, written or applied to the model.
    #[error("{path}: {message}")]
    Weights {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}
