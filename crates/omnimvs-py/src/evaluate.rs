//! `omnimvs.evaluate`: the paper's metrics of a prediction against a frame's ground truth,
//! scored as `omnimvs eval` scores a method.

use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use omnimvs_eval::metrics::{Protocol, index_on_eval_grid, protocol_metrics};
use omnimvs_sweep::EquirectGrid;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{shape_text, type_name};
use crate::dataset::{PyDataset, frame_number};
use crate::error::{IntoPyResult, bad_argument, detached};

/// A prediction as `f64` values and its `(height, width)`.
fn prediction_values(prediction: &Bound<'_, PyAny>) -> PyResult<(Vec<f64>, usize, usize)> {
    let wrong = || {
        let found = prediction.cast::<numpy::PyUntypedArray>().map_or_else(
            |_| type_name(prediction),
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
/// scores a method: the prediction (on its own equirectangular grid over `+-phi_deg`) is
/// resampled on the sphere to the evaluation grid `height x width` (bilinear, longitude
/// wrapping around), turned into hypothesis indices of `ndepth` spheres and scored against the
/// frame's ground truth: per pixel `E = |n_hat - n*| / N * 100`; returns a dict with
/// `over1_pct`, `over3_pct`, `over5_pct` (percent of scored pixels with `E > 1, 3, 5`),
/// `mae`, `rms` and `valid_pixels` (the number of pixels scored).
///
/// Args:
///     prediction: inverse depth (1/m), a 2-D `numpy.float32` (or float64) array on its own
///         grid, e.g. `sgm`'s or the bundled cascade's 160x640, or the bundled `tiny`'s 32x128.
///     dataset: the `omnimvs.Dataset` with the frame's ground truth.
///     frame: the frame.
///     height, width, ndepth: the evaluation grid and its N (the unit of `E`), `omnimvs
///         eval`'s defaults.
///     phi_deg: latitude range of the prediction and of the evaluation grid, +-degrees.
///     protocol: `"reference"` (the reference's evalError, the paper's tables: sky is not
///         scored) or `"with-sky"` (sky scored as index 0, as in training).
///
/// Raises:
///     ValueError: a bad argument, or no ground truth for the frame.
#[pyfunction]
#[pyo3(signature = (prediction, dataset, frame, height=160, width=640, ndepth=192, phi_deg=45.0, protocol="reference"))]
#[allow(clippy::too_many_arguments)]
pub fn evaluate<'py>(
    py: Python<'py>,
    prediction: &Bound<'py, PyAny>,
    dataset: PyRef<'py, PyDataset>,
    frame: i64,
    height: usize,
    width: usize,
    ndepth: usize,
    phi_deg: f64,
    protocol: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let frame = frame_number(frame)?;
    let protocol = Protocol::ALL
        .into_iter()
        .find(|p| p.name() == protocol)
        .ok_or_else(|| {
            bad_argument(
                "protocol",
                format!("expected \"reference\" or \"with-sky\", found {protocol:?}"),
            )
        })?;
    let (inv_depth, rows, cols) = prediction_values(prediction)?;
    let ds = &dataset.inner;
    let metrics = detached(py, || {
        let spec = ds.sweep_spec(height, width, phi_deg, ndepth).py_err()?;
        let (grid, hyps) = (spec.grid, spec.hypotheses);
        let native =
            EquirectGrid::new(rows, cols, phi_deg).map_err(|e| bad_argument("prediction", e))?;
        let Some(truth) = ds.eval_truth(frame, &spec).py_err()? else {
            return Err(bad_argument(
                "frame",
                format!("frame {frame} of {} has no ground truth", ds.root.display()),
            ));
        };
        // Inverse depth as indices of the evaluation's hypotheses on the prediction's grid,
        // then on the evaluation grid, exactly as eval brings a method's output there.
        let native_index: Vec<f32> = inv_depth.iter().map(|&d| hyps.index(d) as f32).collect();
        let index = index_on_eval_grid(&native_index, &native, &hyps, &grid, &hyps).py_err()?;
        protocol_metrics(&index, &truth, ndepth, protocol).py_err()
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

/// How well a predicted inverse-depth map explains the frame's images, without ground truth,
/// as `omnimvs eval` scores real recordings: every pixel with a depth is a point in the rig
/// frame, sampled (bilinear) in every camera that sees it; the median absolute gray difference
/// over camera pairs that see a point, divided by the standard deviation of the gray values
/// sampled. Lower is better; compare methods on the same frame, and against a constant depth.
///
/// Args:
///     prediction: inverse depth (1/m), a 2-D `numpy.float32` (or float64) array on its own
///         equirectangular grid over `+-phi_deg` (e.g. `sgm`'s or `infer`'s 160x640).
///     dataset: the `omnimvs.Dataset` whose frame it is.
///     frame: the frame.
///     phi_deg: latitude range of the prediction, +-degrees.
///
/// Returns:
///     The difference, or `None` when no two cameras share more than 100 points.
///
/// Raises:
///     ValueError: a bad argument. FileNotFoundError / OSError: images that cannot be read.
#[pyfunction]
#[pyo3(signature = (prediction, dataset, frame, phi_deg=45.0))]
pub fn photometric_difference(
    py: Python<'_>,
    prediction: &Bound<'_, PyAny>,
    dataset: PyRef<'_, PyDataset>,
    frame: i64,
    phi_deg: f64,
) -> PyResult<Option<f64>> {
    let frame = frame_number(frame)?;
    let (inv_depth, rows, cols) = prediction_values(prediction)?;
    let ds = &dataset.inner;
    detached(py, || {
        let grid =
            EquirectGrid::new(rows, cols, phi_deg).map_err(|e| bad_argument("prediction", e))?;
        let images = ds.read_frame(frame).py_err()?;
        let inv_depth: Vec<f32> = inv_depth.iter().map(|&v| v as f32).collect();
        Ok(omnimvs_eval::photometric::photometric_difference(
            &ds.rig, &images, &grid, &inv_depth,
        ))
    })
}
