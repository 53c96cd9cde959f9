//! `omnimvs.sgm`: the classical method (spherical-sweep ZNCC + SGM).

use numpy::PyArray2;
use omnimvs_data::{DepthEstimator, Speed};
use omnimvs_net::learned_sgm::{MatchingCost, sgm_estimator};
use omnimvs_stereo::SgmParams;
use pyo3::prelude::*;

use crate::arrays::map_to_array;
use crate::dataset::PyRig;
use crate::error::{IntoPyResult, detached};
use crate::images::frame_source;

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
///     ndepth: number of inverse-depth hypotheses N (even; 192 unless `speed` says).
///     phi_deg: latitude range of the output, +-degrees.
///     rig: the `omnimvs.Rig` of images given as arrays.
///     cost: the matching cost, `"zncc"` (ZNCC+SGM), `"mccnn"` (the bundled MC-CNN-style
///         learned cost, MC-CNN+SGM) or `"sweepnet"` (the bundled SweepNet-style learned cost,
///         SweepNet+SGM), learned costs with their own penalties, as `omnimvs sgm --cost`.
///     speed: `None`, or a speed preset instead of `ndepth`, as `omnimvs sgm --speed`:
///         `"fast"` (32 spheres), `"balanced"` (64) or `"accurate"` (192).
///
/// Raises:
///     FileNotFoundError: an image of the frame is missing.
///     ValueError: a bad argument or array (the message names it).
#[pyfunction]
#[pyo3(signature = (source, frame=None, height=160, width=640, ndepth=None, phi_deg=45.0, *, rig=None, cost="zncc", speed=None))]
#[allow(clippy::too_many_arguments)]
pub fn sgm<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    frame: Option<i64>,
    height: usize,
    width: usize,
    ndepth: Option<usize>,
    phi_deg: f64,
    rig: Option<&Bound<'py, PyRig>>,
    cost: &str,
    speed: Option<&str>,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let ndepth = match (speed, ndepth) {
        (Some(_), Some(_)) => {
            return Err(crate::error::bad_argument(
                "speed",
                "give speed or ndepth, not both",
            ));
        }
        (Some(speed), None) => speed
            .parse::<Speed>()
            .map_err(|e| crate::error::bad_argument("speed", e))?
            .sgm_ndepth(),
        (None, ndepth) => ndepth.unwrap_or(Speed::Accurate.sgm_ndepth()),
    };
    let cost: MatchingCost = cost
        .parse()
        .map_err(|e: omnimvs_net::NetError| crate::error::bad_argument("cost", e.to_string()))?;
    let (ds, images) = frame_source(source, frame, rig)?;
    let inv_depth = detached(py, || {
        let spec = ds.sweep_spec(height, width, phi_deg, ndepth).py_err()?;
        let masks = ds.masks().py_err()?;
        let stereo = sgm_estimator(&ds.rig, masks, spec, cost, "bundled", |(p1, p2)| {
            SgmParams {
                p1,
                p2,
                ..SgmParams::default()
            }
        })
        .py_err()?;
        let images = images.load(&ds)?;
        Ok(stereo.estimate(&images).py_err()?.inv_depth)
    })?;
    map_to_array(py, inv_depth, height, width)
}
