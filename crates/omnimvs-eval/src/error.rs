use std::path::PathBuf;

use omnimvs_data::DataError;
use omnimvs_sweep::SweepError;

/// Errors of scoring and writing outputs; each names the file, or the size that does not fit.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// Reading a dataset, its ground truth, or writing an image or a TIFF.
    #[error(transparent)]
    Data(#[from] DataError),
    /// A size or count that does not fit.
    #[error(transparent)]
    Sweep(#[from] SweepError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
}

impl EvalError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }

    pub(crate) fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::Format {
            path: path.into(),
            message: message.into(),
        }
    }

    /// A size or count that does not fit, as [`SweepError::mismatch`].
    pub(crate) fn mismatch(
        what: impl Into<String>,
        expected: impl ToString,
        found: impl ToString,
    ) -> Self {
        Self::Sweep(SweepError::mismatch(what, expected, found))
    }
}
