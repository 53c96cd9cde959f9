use omnimvs_data::DataError;

/// Errors of scoring and writing outputs: the dataset crate's, whose every message names the
/// file, the field or the size that is not what was expected.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// Reading a dataset or its ground truth, writing a file, or a size that does not fit.
    #[error(transparent)]
    Data(#[from] DataError),
}

impl From<omnimvs_sweep::SweepError> for EvalError {
    fn from(e: omnimvs_sweep::SweepError) -> Self {
        Self::Data(e.into())
    }
}

impl EvalError {
    pub(crate) fn io(path: impl Into<std::path::PathBuf>, source: std::io::Error) -> Self {
        DataError::io(path, source).into()
    }

    pub(crate) fn format(path: impl Into<std::path::PathBuf>, message: impl Into<String>) -> Self {
        DataError::format(path, message).into()
    }

    pub(crate) fn mismatch(
        what: impl Into<String>,
        expected: impl ToString,
        found: impl ToString,
    ) -> Self {
        DataError::mismatch(what, expected, found).into()
    }
}
