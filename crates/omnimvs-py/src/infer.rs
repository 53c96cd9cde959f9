//! `omnimvs.infer`: the OmniMVS network on one frame.

use std::path::{Path, PathBuf};

use numpy::PyArray2;
use omnimvs_data::{DepthEstimator, Finishing, Speed};
use omnimvs_net::bundled::{BundledModel, PickChoice};
use omnimvs_net::pick::PickRefiner;
use omnimvs_net::weights::{AnyNet, common_image_size, load_family};
use omnimvs_net::{Backend, NetConfig, NetEstimator};
use omnimvs_sweep::LutCache;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::map_to_array;
use crate::dataset::PyRig;
use crate::error::{IntoPyResult, bad_argument, detached, with_context};
use crate::images::frame_source;

/// The bundled model `weights` names (`None`: the default one), if any.
fn bundled_model(weights: Option<&Path>) -> Option<BundledModel> {
    match weights {
        None => Some(BundledModel::DEFAULT),
        Some(path) => path.to_str().and_then(BundledModel::from_name),
    }
}

/// The learnt pick after the cascade as `omnimvs infer --pick` chooses it: `"auto"` the bundled
/// model's own (the bundled cascade's two picks), `"off"` none, `"single"` the first bundled
/// pick alone, `"chain"` both, or a pick's `.safetensors`.
fn load_pick(pick: &str, weights: Option<&Path>) -> PyResult<Option<PickRefiner>> {
    PickChoice::parse(pick)
        .load(bundled_model(weights))
        .map_err(|e| with_context(format!("pick {pick}: "), &e))
}

/// Loads the network as `omnimvs infer --weights` does: a bundled model (the default one, the
/// cascade, for `None`, or by name: `"cascade"`, `"tiny"`), or a file of either family (our
/// `.safetensors` with its `.json`, or a reference PyTorch checkpoint sized by `preset`).
fn load_network(
    weights: Option<&Path>,
    preset: &str,
    device: &burn::tensor::Device,
) -> PyResult<AnyNet> {
    let Some(path) = weights else {
        return BundledModel::DEFAULT.load(device).py_err();
    };
    if let Some(model) = path.to_str().and_then(BundledModel::from_name) {
        return model.load(device).py_err();
    }
    let base = NetConfig::preset(preset).py_err()?;
    load_family(path, &base, device)
        .map_err(|e| with_context(format!("weights {}: ", path.display()), &e))
}

/// 360-degree inverse depth by a network, as `omnimvs infer` computes it: a `numpy.float32`
/// array `(height, width)` of inverse depth (1/m) on the network's output grid (160x640 over
/// +-45 degrees, N = 192, for the default bundled cascade; 32x128, N = 64, for the bundled
/// `"tiny"`; a weights file of the paper's network or of the cascade family brings its own).
///
/// Args:
///     source: an `omnimvs.Dataset`, or the frame's images as a list of `numpy.uint8` arrays
///         `(rows, cols)`, one per camera in the rig's order (then `rig` is required).
///     frame: the frame of the dataset (only with a Dataset).
///     weights: `None` for the default bundled model (the cascade), `"cascade"` or `"tiny"`
///         (the paper's network, small) for a bundled model by name, or a weights file: our
///         `.safetensors` (with its `.json` beside it) or a reference PyTorch checkpoint
///         (`.pt`/`.pth`).
///     preset: the sizes of a PyTorch checkpoint, `"paper"` or `"tiny"`.
///     backend: the compute backend, `"cpu"` unless the package was built with the
///         `libtorch` or `wgpu` feature.
///     rig: the `omnimvs.Rig` of images given as arrays.
///     snap_edges: `None` (the default) or a percentage of the hypotheses in (0, 100]: where a
///         pixel's 3x3 neighbourhood spans more than that, the pixel takes the neighbourhood's
///         nearer extreme, so that no point floats between two surfaces (`omnimvs infer
///         --snap-edges`; 8 is the command's default).
///     max_entropy: `None` (the default) or an entropy in nats: the pixels whose uncertainty
///         is above it are NaN (`omnimvs infer --max-entropy`; applied after `snap_edges`).
///     max_spread: `None` (the default) or a spread in index units of N: the same by the
///         standard deviation of the network's distribution, a sharper filter (`omnimvs infer
///         --max-spread`; applied after `max_entropy`).
///     pick: the learnt pick after the cascade network (`omnimvs infer --pick`): `"auto"`
///         (the default: the bundled cascade's own picks after the bundled cascade, its two
///         in turn, none after other weights), `"off"`, `"single"` (the first
///         bundled pick alone), `"chain"` (both), or a pick's `.safetensors` trained on the
///         answers of the `weights` network (several, comma-separated, run in turn).
///     maps: `False` (the default) for the inverse-depth array alone; `True` for a dict of
///         every map of the estimate, each `numpy.float32` `(height, width)` or `None` where
///         the network has none: `inv_depth`, `index` (hypothesis index, N units), `entropy`
///         (nats) and `spread` (standard deviation, index units; the cascade's), the files
///         `omnimvs infer` writes.
///     speed: `None`, or a speed preset instead of `pick` (and the input size), as `omnimvs
///         infer --speed`: `"fast"` (half the model's input size, no pick), `"balanced"` (no
///         pick) or `"accurate"` (the defaults).
///
/// Raises:
///     FileNotFoundError: the weights file or an image of the frame is missing.
///     ValueError: a bad argument or array, or a rig that does not fit the network.
#[pyfunction]
#[pyo3(signature = (source, frame=None, weights=None, *, preset="paper", backend="cpu", rig=None, snap_edges=None, max_entropy=None, max_spread=None, pick="auto", maps=false, speed=None))]
#[allow(clippy::too_many_arguments)]
pub fn infer<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    frame: Option<i64>,
    weights: Option<PathBuf>,
    preset: &str,
    backend: &str,
    rig: Option<&Bound<'py, PyRig>>,
    snap_edges: Option<f64>,
    max_entropy: Option<f32>,
    max_spread: Option<f32>,
    pick: &str,
    maps: bool,
    speed: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let speed = speed
        .map(|s| s.parse::<Speed>().map_err(|e| bad_argument("speed", e)))
        .transpose()?;
    let pick = match speed {
        Some(_) if pick != "auto" => {
            return Err(bad_argument("speed", "give speed or pick, not both"));
        }
        Some(speed) if !speed.net_picks() => "off",
        _ => pick,
    };
    let finishing = Finishing {
        snap_edges_pct: snap_edges,
        max_entropy,
        max_spread,
    }
    .checked()
    .map_err(|e| bad_argument(e.name, &e))?;
    let (ds, images) = frame_source(source, frame, rig)?;
    let backend: Backend = backend.parse().map_err(|e| bad_argument("backend", e))?;
    let result = detached(py, || {
        let device = backend.device().py_err()?;
        let mut net = load_network(weights.as_deref(), preset, &device)?;
        // A reference checkpoint runs at the cameras' own image size, as the reference runs
        // it (and as `omnimvs infer` does by default).
        let is_pytorch = weights
            .as_deref()
            .and_then(Path::extension)
            .is_some_and(|e| e == "pt" || e == "pth");
        if is_pytorch && let Ok(size) = common_image_size(&ds.rig) {
            net.set_input_size(size).py_err()?;
        }
        if let Some(speed) = speed {
            let model_size = [net.config().input_height, net.config().input_width];
            net.set_input_size(speed.net_input_size(model_size))
                .py_err()?;
        }
        let (estimator, _status) = NetEstimator::new(
            net,
            &ds,
            &LutCache::default_location(),
            device,
            backend.is_gpu(),
        )
        .py_err()?;
        let (estimator, note) = estimator
            .with_chosen_pick(
                &PickChoice::parse(pick),
                load_pick(pick, weights.as_deref())?,
            )
            .py_err()?;
        if let Some(note) = note {
            eprintln!("note: {note}");
        }
        let images = images.load(&ds)?;
        let mut estimate = estimator.estimate(&images).py_err()?;
        finishing.apply(&mut estimate);
        Ok(estimate)
    })?;
    let (height, width) = (result.spec.height(), result.spec.width());
    if !maps {
        return Ok(map_to_array(py, result.inv_depth, height, width)?.into_any());
    }
    let dict = PyDict::new(py);
    let optional = |map: Option<Vec<f32>>| -> PyResult<Option<Bound<'py, PyArray2<f32>>>> {
        map.map(|m| map_to_array(py, m, height, width)).transpose()
    };
    dict.set_item(
        "inv_depth",
        map_to_array(py, result.inv_depth, height, width)?,
    )?;
    dict.set_item("index", map_to_array(py, result.index, height, width)?)?;
    dict.set_item("entropy", optional(result.entropy)?)?;
    dict.set_item("spread", optional(result.spread)?)?;
    Ok(dict.into_any())
}
