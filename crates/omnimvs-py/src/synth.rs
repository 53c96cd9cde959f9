//! `omnimvs.synth`: render a synthetic dataset with exact ground truth.

use std::path::PathBuf;

use omnimvs_data::{Dataset, FrameRange};
use omnimvs_synth::random_rig::RANDOM_PREFIX;
use omnimvs_synth::rig::{RigSource, load_rig};
use omnimvs_synth::{DatasetWriter, SceneKind, Shard};
use pyo3::prelude::*;

use crate::arrays::type_name;
use crate::dataset::{PyDataset, PyRig};
use crate::error::{IntoPyResult, bad_argument, bad_type, detached};

/// The rig argument: `None` (the published rig), a `Rig`, or a `config.yaml` path.
fn rig_source(rig: Option<&Bound<'_, PyAny>>) -> PyResult<RigSource> {
    let Some(rig) = rig else {
        return load_rig("sunny").py_err();
    };
    if let Ok(r) = rig.cast::<PyRig>() {
        let ds = &r.get().inner;
        return Ok(RigSource::new(ds.rig.clone(), ds.config.min_depth_m));
    }
    let path: PathBuf = rig.extract().map_err(|_| {
        bad_type(
            "rig",
            format!(
                "expected None (the published rig), an omnimvs.Rig or the path of a config.yaml, found {}",
                type_name(rig)
            ),
        )
    })?;
    let text = path
        .to_str()
        .ok_or_else(|| bad_argument("rig", format!("{}: expected a UTF-8 path", path.display())))?;
    if text == "sunny" || text == "preset" || text.starts_with(RANDOM_PREFIX) {
        return load_rig(text).py_err();
    }
    if !path.is_file() {
        return Err(pyo3::exceptions::PyFileNotFoundError::new_err(format!(
            "rig: {}: no such config.yaml",
            path.display()
        )));
    }
    load_rig(text).py_err()
}

/// The frame range argument: `(first, last)` inclusive, or one frame.
fn frame_range(frames: &Bound<'_, PyAny>) -> PyResult<FrameRange> {
    let (start, end): (i64, i64) = match frames.extract::<i64>() {
        Ok(f) => (f, f),
        Err(_) => frames.extract().map_err(|_| {
            bad_type(
                "frames",
                format!(
                    "expected (first, last) inclusive or one frame number, found {}",
                    type_name(frames)
                ),
            )
        })?,
    };
    let to_u32 = |v: i64| u32::try_from(v).ok();
    match (to_u32(start), to_u32(end)) {
        (Some(start), Some(end)) if start <= end => Ok(FrameRange {
            start,
            step: 1,
            end,
        }),
        _ => Err(bad_argument(
            "frames",
            format!("expected 0 <= first <= last, found ({start}, {end})"),
        )),
    }
}

/// Renders a synthetic omnidirectional stereo dataset, as `omnimvs synth` does: `out/config.yaml`,
/// `out/camN/%05d.png` (8-bit gray fisheyes), `out/omnidepth_gt_640/%05d.tiff` (exact inverse
/// depth, 1/m, 320x640 over +-90 degrees, 0 = sky), `out/scene/%05d.json` and
/// `out/synth.json`. Frames already complete in `out` are skipped (an interrupted run
/// resumes); the same seed and frame give byte-identical files. Returns the new dataset.
///
/// Args:
///     kind: `"things"` (random objects in a room or under a sky) or `"house"` (furnished rooms).
///     out: the output folder (`str` or `pathlib.Path`).
///     frames: `(first, last)`, inclusive, or one frame number.
///     seed: the dataset seed.
///     rig: `None` for the published 4-camera rig, an `omnimvs.Rig`, a rig file (a reference
///         `config.yaml`, a Basalt `calibration.json`, a Kalibr `camchain.yaml`), or
///         `"random:SEED"`: a rig drawn from the seed (2-8 cameras of four lens models).
///     size: `(height, width)` of every camera's images (the rig's intrinsics are rescaled),
///         or `None` for the rig's own.
///     spp: samples per pixel (anti-aliasing).
///
/// Raises:
///     FileNotFoundError: the rig's config.yaml does not exist.
///     OSError: the output folder cannot be written.
///     ValueError: a bad argument, or `out` holds a dataset made with other settings.
#[pyfunction]
#[pyo3(signature = (kind, out, frames=None, seed=0, rig=None, size=None, spp=1))]
#[allow(clippy::too_many_arguments)]
pub fn synth(
    py: Python<'_>,
    kind: &str,
    out: PathBuf,
    frames: Option<&Bound<'_, PyAny>>,
    seed: u64,
    rig: Option<&Bound<'_, PyAny>>,
    size: Option<(u32, u32)>,
    spp: u32,
) -> PyResult<PyDataset> {
    let kind: SceneKind = kind.parse().map_err(|e| bad_argument("kind", e))?;
    let range = match frames {
        Some(f) => frame_range(f)?,
        None => FrameRange {
            start: 1,
            step: 1,
            end: 10,
        },
    };
    let mut source = rig_source(rig)?;
    if let Some((height, width)) = size {
        if height == 0 || width == 0 {
            return Err(bad_argument(
                "size",
                format!("expected (height, width) > 0, found ({height}, {width})"),
            ));
        }
        source = source.resized(height, width).py_err()?;
    }
    if spp == 0 {
        return Err(bad_argument("spp", "expected at least 1 sample per pixel"));
    }
    let inner = detached(py, || {
        let writer = DatasetWriter::create(&out, &source, kind, seed, spp, &[], &range).py_err()?;
        writer.run(&Shard::ALL.frames(&range), |_| {}).py_err()?;
        Dataset::open(&out).py_err()
    })?;
    Ok(PyDataset { inner })
}
