//! Python bindings of omnimvs (module `omnimvs._omnimvs`, re-exported by the `omnimvs`
//! package): datasets, lookup tables, the classical method (ZNCC + SGM), the network, the
//! paper's metrics and the synthetic-data generator, with numpy arrays in and out.
//!
//! Every function calls the library crates exactly as the `omnimvs` command does, releases
//! the GIL while it computes, and turns library errors into `ValueError`,
//! `FileNotFoundError` or `OSError` carrying the library's message (`error`).
//!
//! - `dataset`: `Dataset` and `Rig`, the geometry every other function takes.
//! - `images`: numpy arrays to and from gray images, with checks that name the argument.
//! - `lut`, `sgm`, `infer`, `evaluate`, `synth`: one Python function each.

mod arrays;
mod dataset;
mod error;
mod evaluate;
mod images;
mod infer;
mod lut;
mod sgm;
mod synth;

use pyo3::prelude::*;

/// The compiled part of the `omnimvs` package; import `omnimvs` instead.
#[pymodule]
fn _omnimvs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<dataset::PyDataset>()?;
    m.add_class::<dataset::PyRig>()?;
    m.add_function(wrap_pyfunction!(lut::lookup_table, m)?)?;
    m.add_function(wrap_pyfunction!(sgm::sgm, m)?)?;
    m.add_function(wrap_pyfunction!(infer::infer, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::photometric_difference, m)?)?;
    m.add_function(wrap_pyfunction!(synth::synth, m)?)?;
    Ok(())
}
