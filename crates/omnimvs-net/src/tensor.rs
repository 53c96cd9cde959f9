//! Generic helpers on burn tensors: their values read back to the host as `f32` and small
//! tensors built from host values. Nothing else in the crate is imported here, so every
//! module may use it.

use burn::tensor::{Device, Tensor, TensorData};

use crate::error::NetError;

/// Reads a `[B, H, W]` (or any) tensor's values.
///
/// # Errors
/// [`NetError::Shape`] when the data cannot be read as `f32`.
pub fn read_values<const D: usize>(t: Tensor<D>, what: &str) -> Result<Vec<f32>, NetError> {
    t.into_data()
        .try_into_vec_as::<f32>()
        .map_err(|e| NetError::Shape {
            what: format!("{what} ({e:?})"),
            expected: vec![],
            actual: vec![],
        })
}

/// `f` on the values of `t` as `f32`, borrowed from the tensor's buffer: no copy when the
/// tensor holds its values alone, one when it shares them (where [`read_values`] of a shared
/// tensor copies twice).
///
/// # Errors
/// [`NetError::Shape`] when the data cannot be read as `f32`.
pub fn with_values<const D: usize, R>(
    t: Tensor<D>,
    what: &str,
    f: impl FnOnce(&[f32]) -> R,
) -> Result<R, NetError> {
    let data = t.into_data();
    if let Ok(values) = data.as_slice::<f32>() {
        return Ok(f(values));
    }
    // Another dtype, or bytes not aligned for f32: converted in a copy.
    let values = data.try_into_vec_as::<f32>().map_err(|e| NetError::Shape {
        what: format!("{what} ({e:?})"),
        expected: vec![],
        actual: vec![],
    })?;
    Ok(f(&values))
}

/// A `[1, K, H, W]` tensor of hypothesis indices from `[K, H * W]` values.
pub fn hypothesis_tensor(
    values: Vec<f32>,
    k: usize,
    h: usize,
    w: usize,
    device: &Device,
) -> Tensor<4> {
    Tensor::from_data(TensorData::new(values, [1, k, h, w]), device)
}
