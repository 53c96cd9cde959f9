//! YAML helpers shared by the configuration readers: parse once into a
//! generic value, then deserialise with the path of the failing field.

use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// Errors of the YAML helpers; each names the file (or what was written) and, where there is
/// one, the field.
#[derive(Debug, thiserror::Error)]
pub enum YamlError {
    #[error("{path}: not valid YAML: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error("{path}: field `{field}`: {message}")]
    Field {
        path: PathBuf,
        field: String,
        message: String,
    },
    #[error("cannot write {what} as YAML: {message}")]
    Write { what: String, message: String },
}

/// Parses YAML text into a generic value.
///
/// # Errors
/// [`YamlError::Syntax`] naming the file, for malformed or empty YAML.
pub fn parse_yaml(path: &Path, text: &str) -> Result<serde_json::Value, YamlError> {
    if text.trim().is_empty() {
        return Err(YamlError::Syntax {
            path: path.to_path_buf(),
            message: "the file is empty".to_string(),
        });
    }
    serde_saphyr::from_str::<serde_json::Value>(text).map_err(|e| YamlError::Syntax {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Deserialises a typed structure from a parsed value, naming the failing
/// field (`cameras[1].poly[3]`) in the error.
///
/// # Errors
/// [`YamlError::Field`] for a missing field or a value of the wrong type.
pub fn from_value<T: DeserializeOwned>(
    path: &Path,
    value: serde_json::Value,
) -> Result<T, YamlError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let field = e.path().to_string();
        let field = if field == "." {
            "(top level)".to_string()
        } else {
            field
        };
        YamlError::Field {
            path: path.to_path_buf(),
            field,
            message: e.into_inner().to_string(),
        }
    })
}

/// Writes a value as block-style YAML with the reference's layout: two-space indents, list
/// items indented under their key (`cameras:\n  - cam_id: 1`); lists and strings as the
/// value's types ask (e.g. `serde_saphyr::FlowSeq`, `DoubleQuoted`).
///
/// # Errors
/// [`YamlError::Write`] naming `what` if the serialiser refuses the value.
pub fn to_yaml<T: Serialize>(what: &str, value: &T) -> Result<String, YamlError> {
    let mut options = serde_saphyr::SerializerOptions::default();
    options.indent_step = 2;
    options.compact_list_indent = false;
    serde_saphyr::to_string_with_options(value, options).map_err(|e| YamlError::Write {
        what: what.to_string(),
        message: e.to_string(),
    })
}
