//! numpy arrays from Rust values, and how Python things are named in messages.

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use omnimvs_core::{ColourPlanes, GrayImage};
use pyo3::prelude::*;
use pyo3::types::PyTypeMethods;

use crate::error::bad_argument;

/// A gray image as a `numpy.uint8` array `(height, width)` (values rounded; 16-bit images
/// were scaled to 0..255 when read).
pub fn gray_to_array<'py>(
    py: Python<'py>,
    image: &GrayImage,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let pixels: Vec<u8> = image
        .data
        .iter()
        .map(|&v| v.round().clamp(0.0, 255.0) as u8)
        .collect();
    PyArray1::from_vec(py, pixels)
        .reshape([image.height, image.width])
        .map_err(|e| bad_argument("image", e))
}

/// A colour image as a `numpy.uint8` array `(height, width, 3)`, RGB (values rounded; 16-bit
/// images were scaled to 0..255 when read).
pub fn colour_to_array<'py>(
    py: Python<'py>,
    image: &ColourPlanes,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    PyArray1::from_vec(py, image.to_rgb8())
        .reshape([image.height(), image.width(), 3])
        .map_err(|e| bad_argument("image", e))
}

/// A `(height, width)` float32 map as a numpy array.
pub fn map_to_array(
    py: Python<'_>,
    data: Vec<f32>,
    height: usize,
    width: usize,
) -> PyResult<Bound<'_, PyArray2<f32>>> {
    PyArray1::from_vec(py, data)
        .reshape([height, width])
        .map_err(|e| bad_argument("result", e))
}

/// A shape as Python writes it: `(768, 800)`, `(3,)`.
pub fn shape_text(shape: &[usize]) -> String {
    let items: Vec<String> = shape.iter().map(ToString::to_string).collect();
    match items.len() {
        1 => format!("({},)", items[0]),
        _ => format!("({})", items.join(", ")),
    }
}

/// The Python type name of `obj`, for messages.
pub fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "an object".into(), |n| n.to_string())
}
