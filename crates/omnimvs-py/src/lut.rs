//! `omnimvs.lookup_table`: the spherical-sweep lookup table in the reference `.hwd` layout.

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use omnimvs_sweep::{LutCache, SphereSet};
use pyo3::prelude::*;

use crate::dataset::geometry;
use crate::error::{IntoPyResult, bad_argument, detached};

/// The lookup table of a rig, exactly what `omnimvs lut` writes to `lt_(h,w,N).hwd`: a
/// `numpy.float32` array `[cameras, ndepth/2, height, width, 2]` of sampling positions
/// `(x, y)` in each camera's image, normalised for `grid_sample(align_corners=True)`, for
/// every other one of the `ndepth` spheres; entries a camera does not see lie far outside
/// `[-1, 1]`. Tables are cached in `$OMNIMVS_CACHE_DIR/lut` (default `~/.cache/omnimvs/lut`),
/// as by the command line.
///
/// Args:
///     source: an `omnimvs.Dataset` or `omnimvs.Rig`.
///     height, width: the equirectangular output grid.
///     ndepth: number of inverse-depth hypotheses N (even, at least 2).
///     phi_deg: latitude range of the grid, +-degrees.
///
/// Raises:
///     ValueError: a bad argument (the message names it).
#[pyfunction]
#[pyo3(signature = (source, height=160, width=640, ndepth=192, phi_deg=45.0))]
pub fn lookup_table<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    height: usize,
    width: usize,
    ndepth: usize,
    phi_deg: f64,
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let ds = geometry(source, "source")?;
    if ndepth < 2 || !ndepth.is_multiple_of(2) {
        return Err(bad_argument(
            "ndepth",
            format!(
                "expected an even number of at least 2 (the table holds every other sphere), found {ndepth}"
            ),
        ));
    }
    let lut = detached(py, || {
        let spec = ds.sweep_spec(height, width, phi_deg, ndepth).py_err()?;
        let (lut, _status) = LutCache::default_location()
            .load_or_build(&ds.rig, &spec.grid, &spec.hypotheses, SphereSet::EveryOther)
            .py_err()?;
        Ok(lut)
    })?;
    let shape = [lut.num_cameras(), lut.num_spheres(), height, width, 2];
    PyArray1::from_vec(py, lut.data)
        .reshape(shape.as_slice())
        .map_err(|e| bad_argument("lookup table", e))
}
