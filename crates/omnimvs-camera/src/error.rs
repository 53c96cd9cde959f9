use std::path::PathBuf;

/// Errors of the camera crate. Every variant names the file and, where there
/// is one, the field that was wrong.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Malformed YAML, a field of the wrong type, or a value the writer refuses.
    #[error(transparent)]
    Yaml(#[from] omnimvs_core::yaml::YamlError),
    #[error("{path}: field `{field}`: {message}")]
    Field {
        path: PathBuf,
        field: String,
        message: String,
    },
    /// A camera model parameter outside the model's valid range.
    #[error("{model} camera model: parameter `{param}`: {message}")]
    Param {
        /// The model's short name, e.g. `ds`.
        model: &'static str,
        /// The parameter's name as the calibration tools write it, e.g. `alpha`.
        param: &'static str,
        message: String,
    },
    /// The rig frame asked for cannot be built from the rig.
    #[error("rig frame: {0}")]
    Frame(String),
    #[error("{path}: line {line}: {message}")]
    Line {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: cannot decode mask image: {source}")]
    MaskImage {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error(
        "{path}: mask is {found_w}x{found_h} pixels, expected {want_w}x{want_h} (the camera's image_size)"
    )]
    MaskSize {
        path: PathBuf,
        found_w: u32,
        found_h: u32,
        want_w: u32,
        want_h: u32,
    },
}

impl CameraError {
    pub(crate) fn field(
        path: impl Into<PathBuf>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::Field {
            path: path.into(),
            field: field.into(),
            message: message.into(),
        }
    }

    pub(crate) fn param(
        model: &'static str,
        param: &'static str,
        message: impl Into<String>,
    ) -> Self {
        Self::Param {
            model,
            param,
            message: message.into(),
        }
    }
}
