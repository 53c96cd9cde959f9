use std::path::PathBuf;

use omnimvs_camera::CameraError;
use omnimvs_sweep::SweepError;

/// Errors of the data crate; each names the file and, where there is one,
/// the field or what was expected.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error(transparent)]
    Sweep(#[from] SweepError),
    #[error(transparent)]
    Yaml(#[from] omnimvs_core::yaml::YamlError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: cannot decode image: {source}")]
    Image {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("{path}: image is {found_w}x{found_h} pixels, expected {want_w}x{want_h} ({what})")]
    ImageSize {
        path: PathBuf,
        found_w: usize,
        found_h: usize,
        want_w: usize,
        want_h: usize,
        what: String,
    },
    #[error("frame {frame} of camera {camera} not found: tried {tried}")]
    MissingFrame {
        frame: u32,
        camera: usize,
        tried: String,
    },
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    #[error("{path}: field `{field}`: {message}")]
    Field {
        path: PathBuf,
        field: String,
        message: String,
    },
    #[error("frame range {text:?}: {message}")]
    FrameRange { text: String, message: String },
}

impl DataError {
    /// A file that cannot be read or written.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }

    /// A file whose content is not what was expected.
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::Format {
            path: path.into(),
            message: message.into(),
        }
    }

    /// A size or count that does not fit, as [`SweepError::mismatch`].
    pub fn mismatch(
        what: impl Into<String>,
        expected: impl ToString,
        found: impl ToString,
    ) -> Self {
        Self::Sweep(SweepError::mismatch(what, expected, found))
    }
}
