use std::path::PathBuf;

use omnimvs_camera::CameraError;

/// Errors of the synthetic dataset generator. Every variant names the file,
/// the option or the field that was wrong.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error(transparent)]
    Data(#[from] omnimvs_data::DataError),
    #[error(transparent)]
    Sweep(#[from] omnimvs_sweep::SweepError),
    #[error("{path}: {action}: {source}")]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error("invalid {what}: {message}")]
    Invalid { what: String, message: String },
    #[error("{path}: mesh: {message}")]
    Mesh { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    Json { path: PathBuf, message: String },
    #[error("{path}: cannot encode image: {message}")]
    Encode { path: PathBuf, message: String },
    #[error(
        "{path}: the folder holds a dataset made with other settings ({message}); \
         write to another folder, or use the same settings to resume"
    )]
    SettingsMismatch { path: PathBuf, message: String },
}

impl SynthError {
    pub(crate) fn invalid(what: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Invalid {
            what: what.into(),
            message: message.into(),
        }
    }

    pub(crate) fn io(
        path: impl Into<PathBuf>,
        action: &'static str,
        source: std::io::Error,
    ) -> Self {
        Self::Io {
            path: path.into(),
            action,
            source,
        }
    }
}
