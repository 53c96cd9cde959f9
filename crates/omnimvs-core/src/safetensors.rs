//! The one safetensors reader for weights read outside burn's records (the pick networks, the
//! training scripts' fixtures). It decodes through the `safetensors` crate, the parser burn's
//! own store uses, so there is one reading of the format in the build.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use safetensors::{Dtype, SafeTensors};

/// Tensors by name: shape and values.
pub type Tensors = HashMap<String, (Vec<usize>, Vec<f32>)>;

/// A file that is not safetensors, or holds something other than `F32` tensors.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct SafetensorsError {
    /// The file (or the label of the bytes).
    pub path: PathBuf,
    /// What was wrong, naming the tensor or key where there is one.
    pub message: String,
}

/// A safetensors file's tensors (`F32` only) and the header's `__metadata__` (empty without
/// one); `path` labels errors.
///
/// # Errors
/// [`SafetensorsError`] for bytes that are not a whole safetensors file (a bad or truncated
/// header, offsets that do not cover the data) or a tensor of another dtype.
pub fn read_safetensors(
    bytes: &[u8],
    path: &Path,
) -> Result<(Tensors, HashMap<String, String>), SafetensorsError> {
    let bad = |message: String| SafetensorsError {
        path: path.to_path_buf(),
        message,
    };
    let file = SafeTensors::deserialize(bytes)
        .map_err(|e| bad(format!("not a whole safetensors file: {e}")))?;
    let (_, header) = SafeTensors::read_metadata(bytes)
        .map_err(|e| bad(format!("not a whole safetensors file: {e}")))?;
    let metadata = header.metadata().clone().unwrap_or_default();
    let mut tensors = HashMap::new();
    for (name, view) in file.iter() {
        if view.dtype() != Dtype::F32 {
            return Err(bad(format!(
                "tensor `{name}`: dtype must be F32, found {:?}",
                view.dtype()
            )));
        }
        let values = view
            .data()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        tensors.insert(name.to_string(), (view.shape().to_vec(), values));
    }
    Ok((tensors, metadata))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file written by hand: header length, JSON header, little-endian data.
    fn file(header: &str, data: &[f32]) -> Vec<u8> {
        let mut bytes = (header.len() as u64).to_le_bytes().to_vec();
        bytes.extend_from_slice(header.as_bytes());
        for v in data {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes
    }

    #[test]
    fn reads_tensors_and_metadata_and_refuses_bad_files() {
        let header = r#"{"__metadata__":{"zncc":"5"},"a":{"dtype":"F32","shape":[2,1],"data_offsets":[0,8]},"b":{"dtype":"F32","shape":[1],"data_offsets":[8,12]}}"#;
        let bytes = file(header, &[1.5, -2.0, 3.25]);
        let path = Path::new("x.safetensors");
        let (tensors, metadata) = read_safetensors(&bytes, path).unwrap();
        assert_eq!(tensors["a"], (vec![2, 1], vec![1.5, -2.0]));
        assert_eq!(tensors["b"], (vec![1], vec![3.25]));
        assert_eq!(metadata["zncc"], "5");
        // Truncated data, garbage, another dtype: errors naming the file.
        let err = read_safetensors(&bytes[..bytes.len() - 2], path).unwrap_err();
        assert!(err.to_string().starts_with("x.safetensors: "), "{err}");
        assert!(read_safetensors(b"abc", path).is_err());
        let header = r#"{"a":{"dtype":"F16","shape":[2],"data_offsets":[0,4]}}"#;
        let err = read_safetensors(&file(header, &[0.0]), path).unwrap_err();
        assert!(
            err.to_string().contains("tensor `a`: dtype must be F32"),
            "{err}"
        );
    }
}
