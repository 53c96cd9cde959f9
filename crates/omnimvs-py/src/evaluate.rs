//! `omnimvs.evaluate`: the paper's metrics of a prediction against a frame's ground truth.

use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use omnimvs_data::metrics::frame_metrics;
use omnimvs_sweep::EquirectGrid;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::dataset::{PyDataset, frame_number};
use crate::error::{IntoPyResult, bad_argument, detached};
use crate::images::shape_text;

/// A prediction as `f64` values and its `(height, width)`.
fn prediction_values(prediction: &Bound<'_, PyAny>) -> PyResult<(Vec<f64>, usize, usize)> {
    let wrong = || {
        let found = prediction.cast::<numpy::PyUntypedArray>().map_or_else(
            |_| crate::dataset::type_name(prediction),
            |a| format!("{} array of shape {}", a.dtype(), shape_text(a.shape())),
        );
        bad_argument(
            "prediction",
            format!(
                "expected a 2-D numpy float32 or float64 array of inverse depth (1/m), found {found}"
            ),
        )
    };
    if let Ok(a) = prediction.cast::<PyArray2<f32>>() {
        let view = a
            .try_readonly()
            .map_err(|e| bad_argument("prediction", e))?;
        let [h, w] = [a.shape()[0], a.shape()[1]];
        return Ok((
            view.as_array().iter().map(|&v| f64::from(v)).collect(),
            h,
            w,
        ));
    }
    if let Ok(a) = prediction.cast::<PyArray2<f64>>() {
        let view = a
            .try_readonly()
            .map_err(|e| bad_argument("prediction", e))?;
        let [h, w] = [a.shape()[0], a.shape()[1]];
        return Ok((view.as_array().iter().copied().collect(), h, w));
    }
    Err(wrong())
}

/// The paper's metrics of a predicted inverse-depth map on one frame, as `omnimvs eval`
/// computes them: per pixel `E = |n_hat - n*| / N * 100` (hypothesis indices of `ndepth`
/// spheres), over the pixels valid in the ground truth (the reference's invalid rule at full
/// resolution, sampled at the prediction grid's rays); returns a dict with `over1_pct`,
/// `over3_pct`, `over5_pct` (percent of pixels with `E > 1, 3, 5`), `mae`, `rms` and
/// `valid_pixels`.
///
/// Args:
///     prediction: inverse depth (1/m), a 2-D `numpy.float32` (or float64) array
///         `(height, width)` on an equirectangular grid of `+-phi_deg` latitude.
///     dataset: the `omnimvs.Dataset` with the frame's ground truth.
///     frame: the frame.
///     ndepth: N of the method (192 for `sgm`'s default, 64 for the bundled network).
///     phi_deg: latitude range of the prediction, +-degrees.
///
/// Raises:
///     ValueError: a bad argument, or no ground truth for the frame.
#[pyfunction]
#[pyo3(signature = (prediction, dataset, frame, ndepth=192, phi_deg=45.0))]
pub fn evaluate<'py>(
    py: Python<'py>,
    prediction: &Bound<'py, PyAny>,
    dataset: PyRef<'py, PyDataset>,
    frame: i64,
    ndepth: usize,
    phi_deg: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let frame = frame_number(frame)?;
    let (inv_depth, height, width) = prediction_values(prediction)?;
    let ds = &dataset.inner;
    let metrics = detached(py, || {
        let grid = EquirectGrid::new(height, width, phi_deg).py_err()?;
        let hyps = ds.hypotheses(ndepth).py_err()?;
        let Some(gt) = ds.ground_truth(frame, &grid, &hyps).py_err()? else {
            return Err(bad_argument(
                "frame",
                format!("frame {frame} of {} has no ground truth", ds.root.display()),
            ));
        };
        let index: Vec<f32> = inv_depth.iter().map(|&d| hyps.index(d) as f32).collect();
        frame_metrics(&index, &gt, ndepth).py_err()
    })?;
    let dict = PyDict::new(py);
    dict.set_item("over1_pct", metrics.over1_pct)?;
    dict.set_item("over3_pct", metrics.over3_pct)?;
    dict.set_item("over5_pct", metrics.over5_pct)?;
    dict.set_item("mae", metrics.mae)?;
    dict.set_item("rms", metrics.rms)?;
    dict.set_item("valid_pixels", metrics.valid_pixels)?;
    Ok(dict)
}
