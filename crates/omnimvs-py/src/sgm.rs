//! `omnimvs.sgm`: the classical method (spherical-sweep ZNCC + SGM).

use numpy::PyArray2;
use omnimvs_data::DepthEstimator;
use omnimvs_stereo::{SgmEstimator, SgmParams};
use pyo3::prelude::*;

use crate::dataset::PyRig;
use crate::error::{IntoPyResult, detached};
use crate::images::{frame_source, map_to_array};

/// 360-degree inverse depth by the classical method of the paper's Table 3 (9x9 ZNCC over
/// every camera pair on a spherical sweep, SGM along 8 paths wrapping round in longitude,
/// winner-take-all with parabola refinement), as `omnimvs sgm` computes it with its default
/// penalties: a `numpy.float32` array `(height, width)` of inverse depth (1/m).
///
/// Args:
///     source: an `omnimvs.Dataset`, or the frame's images as a list of `numpy.uint8` arrays
///         `(rows, cols)`, one per camera in the rig's order (then `rig` is required).
///     frame: the frame of the dataset (only with a Dataset).
///     height, width: the equirectangular output grid.
///     ndepth: number of inverse-depth hypotheses N (even).
///     phi_deg: latitude range of the output, +-degrees.
///     rig: the `omnimvs.Rig` of images given as arrays.
///     cost: the matching cost, `"zncc"` (ZNCC+SGM) or `"mccnn"` (the bundled MC-CNN-style
///         learned cost, MC-CNN+SGM, with its own penalties), as `omnimvs sgm --cost`.
///
/// Raises:
///     FileNotFoundError: an image of the frame is missing.
///     ValueError: a bad argument or array (the message names it).
#[pyfunction]
#[pyo3(signature = (source, frame=None, height=160, width=640, ndepth=192, phi_deg=45.0, *, rig=None, cost="zncc"))]
#[allow(clippy::too_many_arguments)]
pub fn sgm<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    frame: Option<i64>,
    height: usize,
    width: usize,
    ndepth: usize,
    phi_deg: f64,
    rig: Option<&Bound<'py, PyRig>>,
    cost: &str,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    if !matches!(cost, "zncc" | "mccnn") {
        return Err(crate::error::bad_argument(
            "cost",
            format!("{cost:?}: expected \"zncc\" or \"mccnn\""),
        ));
    }
    let (ds, images) = frame_source(source, frame, rig)?;
    let inv_depth = detached(py, || {
        let spec = ds.sweep_spec(height, width, phi_deg, ndepth).py_err()?;
        let masks = ds.masks().py_err()?;
        let stereo = if cost == "mccnn" {
            let device = burn::tensor::Device::flex();
            let net = omnimvs_net::mccnn::bundled(&device).py_err()?;
            let params = SgmParams {
                p1: net.config.p1,
                p2: net.config.p2,
                ..SgmParams::default()
            };
            let extractor = omnimvs_net::mccnn::McCnnExtractor {
                net,
                masks: Some(masks.clone()),
                device,
            };
            SgmEstimator::new(&ds.rig, Some(masks), spec, params)
                .py_err()?
                .with_features(Some(extractor.shared()))
        } else {
            SgmEstimator::new(&ds.rig, Some(masks), spec, SgmParams::default()).py_err()?
        };
        let images = images.load(&ds)?;
        Ok(stereo.estimate(&images).py_err()?.inv_depth)
    })?;
    map_to_array(py, inv_depth, height, width)
}
