//! `omnimvs.Dataset` (a dataset folder) and `omnimvs.Rig` (the geometry of a rig, for frames
//! that come from elsewhere than files).

use std::path::PathBuf;

use numpy::{PyArray2, PyArrayMethods};
use omnimvs_data::Dataset;
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::arrays::{colour_to_array, gray_to_array, type_name};
use crate::error::{IntoPyResult, bad_argument, bad_type, detached};

/// A frame number from Python: a non-negative int.
pub fn frame_number(frame: i64) -> PyResult<u32> {
    u32::try_from(frame).map_err(|_| {
        bad_argument(
            "frame",
            format!("expected a non-negative frame number, found {frame}"),
        )
    })
}

/// A dataset folder (a reference `config.yaml` with the rig, the minimum depth, `img_fmt` and
/// the frame range, plus the images; or a calibration file and one image folder per camera),
/// read exactly as the `omnimvs` command reads it. Nothing is ever written into the folder.
///
/// Args:
///     path: the dataset folder or its `config.yaml` (`str` or `pathlib.Path`), a folder in
///         the released datasets' layout (`ocam1.txt`.. and `poses.txt`), or a folder with a
///         Basalt `calibration.json` or Kalibr `camchain.yaml` and `cam0/`.. (or `cam1/`..).
///     pose_unit: unit of a released-layout folder's `poses.txt` translations, `"m"`, `"cm"`
///         (the released sets' unit, the default) or `"mm"` (SweepNet's real_indoor_sample);
///         a `config.yaml`'s poses are metres and take no other unit.
///     rig_frame: `"calibration"` (the default: the calibration file's own frame) or
///         `"fitted"` (centred at the cameras' mean, vertical axis normal to their plane).
///     min_depth: the sweep's minimum depth in metres, instead of the dataset's.
///
/// Raises:
///     FileNotFoundError: no `config.yaml` there.
///     ValueError: a `config.yaml` field is missing or wrong (the message names it), or an
///         unknown or inapplicable `pose_unit`.
#[pyclass(name = "Dataset", module = "omnimvs", frozen)]
pub struct PyDataset {
    pub inner: Dataset,
}

#[pymethods]
impl PyDataset {
    #[new]
    #[pyo3(signature = (path, pose_unit = None, rig_frame = None, min_depth = None))]
    fn new(
        py: Python<'_>,
        path: PathBuf,
        pose_unit: Option<&str>,
        rig_frame: Option<&str>,
        min_depth: Option<f64>,
    ) -> PyResult<Self> {
        let mut options = open_options(rig_frame, min_depth)?;
        options.pose_unit = pose_unit
            .map(str::parse::<omnimvs_camera::LengthUnit>)
            .transpose()
            .map_err(pyo3::exceptions::PyValueError::new_err)?;
        let inner = detached(py, || Dataset::open_with(&path, &options).py_err())?;
        Ok(Self { inner })
    }

    /// The frame the rig and the outputs are expressed in, in words.
    #[getter]
    fn rig_frame(&self) -> String {
        self.inner.frame.describe()
    }

    /// The dataset folder.
    #[getter]
    fn root(&self) -> PathBuf {
        self.inner.root.clone()
    }

    /// The frames of the configured range whose images all exist (`list[int]`).
    #[getter]
    fn frames(&self, py: Python<'_>) -> PyResult<Vec<u32>> {
        detached(py, || Ok(self.inner.frames_found()))
    }

    /// Number of cameras of the rig.
    #[getter]
    fn num_cameras(&self) -> usize {
        self.inner.rig.len()
    }

    /// Minimum depth of the sweep (`config.omnimvs_sweep_min_depth`), metres.
    #[getter]
    fn min_depth(&self) -> f64 {
        self.inner.config.min_depth_m
    }

    /// The rig of the dataset.
    #[getter]
    fn rig(&self) -> PyRig {
        PyRig {
            inner: self.inner.clone(),
        }
    }

    /// The images of every camera at `frame`, in the rig's camera order: by default gray, a
    /// list of `numpy.uint8` arrays `(height, width)` (a colour image as the mean of its
    /// channels, what the methods match on); with `colour=True` as decoded, a colour image as
    /// `numpy.uint8` `(height, width, 3)` (RGB) and a gray one as `(height, width)`.
    ///
    /// Raises:
    ///     FileNotFoundError: an image of the frame is missing (the message lists the paths tried).
    ///     ValueError: an image has another size than its camera's.
    #[pyo3(signature = (frame, colour = false))]
    fn images<'py>(
        &self,
        py: Python<'py>,
        frame: i64,
        colour: bool,
    ) -> PyResult<Bound<'py, PyList>> {
        let frame = frame_number(frame)?;
        if !colour {
            let images = detached(py, || self.inner.read_frame(frame).py_err())?;
            let arrays = images
                .iter()
                .map(|image| gray_to_array(py, image))
                .collect::<PyResult<Vec<_>>>()?;
            return PyList::new(py, arrays);
        }
        let images = detached(py, || self.inner.read_decoded_frame(frame).py_err())?;
        let arrays = images
            .iter()
            .map(|image| match &image.colour {
                Some(rgb) => colour_to_array(py, rgb).map(Bound::into_any),
                None => gray_to_array(py, &image.gray).map(Bound::into_any),
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, arrays)
    }

    /// The ground-truth inverse depth (1/m) of `frame` as stored (`numpy.float32`,
    /// `(rows, cols)`, typically 320x640 over +-90 degrees; 0 where there is no surface), or
    /// `None` when the dataset has no ground truth for the frame.
    ///
    /// Raises:
    ///     FileNotFoundError: the frame has neither ground truth nor images.
    ///     OSError, ValueError: the ground-truth file cannot be read.
    fn ground_truth<'py>(
        &self,
        py: Python<'py>,
        frame: i64,
    ) -> PyResult<Option<Bound<'py, PyArray2<f32>>>> {
        let frame = frame_number(frame)?;
        let map = detached(py, || {
            let map = self.inner.read_gt(frame).py_err()?;
            if map.is_none() && !self.inner.has_frame(frame) {
                // Neither ground truth nor images: say which files were looked for.
                self.inner.image_path(0, frame).py_err()?;
            }
            Ok(map)
        })?;
        map.map(|m| {
            numpy::PyArray1::from_vec(py, m.data)
                .reshape([m.height, m.width])
                .map_err(|e| bad_argument("ground truth", e))
        })
        .transpose()
    }

    fn __repr__(&self) -> String {
        repr("Dataset", &self.inner.root, &self.inner)
    }
}

/// The geometry of a rig (cameras, poses, minimum depth, validity masks), for images that do
/// not come from a dataset folder, e.g. a robot's live frames: `sgm(images, rig=rig)`.
#[pyclass(name = "Rig", module = "omnimvs", frozen)]
pub struct PyRig {
    /// The rig's `config.yaml` read as a dataset (its images are never read).
    pub inner: Dataset,
}

#[pymethods]
impl PyRig {
    /// Reads the rig of a reference `config.yaml` (or of the dataset folder holding it):
    /// cameras, poses, `config.omnimvs_sweep_min_depth`; validity masks named there are read
    /// relative to its folder.
    ///
    /// Raises:
    ///     FileNotFoundError: no such file.
    ///     ValueError: a field is missing or wrong (the message names it).
    #[staticmethod]
    fn from_config(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        Self::from_file(py, path, None, None)
    }

    /// Reads the rig of any calibration file omnimvs reads (a reference `config.yaml`, a
    /// Basalt `calibration.json`, a Kalibr `camchain.yaml`, or a folder holding one or the
    /// released layout's `ocamN.txt` + `poses.txt`), in `rig_frame` (`"calibration"`, the
    /// default, or `"fitted"`), with the sweep's minimum depth `min_depth` in metres
    /// (default: the file's, else 0.55). Images need not exist.
    ///
    /// Raises:
    ///     FileNotFoundError: no such file.
    ///     ValueError: a field is missing or wrong (the message names the file and the field).
    #[staticmethod]
    #[pyo3(signature = (path, rig_frame = None, min_depth = None))]
    fn from_file(
        py: Python<'_>,
        path: PathBuf,
        rig_frame: Option<&str>,
        min_depth: Option<f64>,
    ) -> PyResult<Self> {
        let options = omnimvs_data::OpenOptions {
            rig_only: true,
            ..open_options(rig_frame, min_depth)?
        };
        let inner = detached(py, || Dataset::open_with(&path, &options).py_err())?;
        Ok(Self { inner })
    }

    /// The model name of each camera (`"ocam"`, `"ds"`, `"eucm"`, `"ucm"`, `"kb4"`,
    /// `"pinhole-radtan"`), in the rig's order.
    #[getter]
    fn models(&self) -> Vec<&'static str> {
        self.inner
            .rig
            .cameras
            .iter()
            .map(|c| c.model.name())
            .collect()
    }

    /// Each camera's `rig_from_cam` as a 4x4 nested list (metres), in the rig's order.
    #[getter]
    fn rig_from_cam(&self) -> Vec<[[f64; 4]; 4]> {
        self.inner
            .rig
            .cameras
            .iter()
            .map(|c| {
                let m = c.rig_from_cam.to_homogeneous();
                std::array::from_fn(|r| std::array::from_fn(|k| m[(r, k)]))
            })
            .collect()
    }

    /// Number of cameras.
    #[getter]
    fn num_cameras(&self) -> usize {
        self.inner.rig.len()
    }

    /// `(height, width)` of each camera's images, in the rig's order.
    #[getter]
    fn image_sizes(&self) -> Vec<(u32, u32)> {
        self.inner
            .rig
            .cameras
            .iter()
            .map(|c| (c.model.height(), c.model.width()))
            .collect()
    }

    /// Minimum depth of the sweep, metres.
    #[getter]
    fn min_depth(&self) -> f64 {
        self.inner.config.min_depth_m
    }

    fn __repr__(&self) -> String {
        repr("Rig", &self.inner.config_path, &self.inner)
    }
}

/// The options of `rig_frame` and `min_depth` as the Python functions take them.
fn open_options(
    rig_frame: Option<&str>,
    min_depth: Option<f64>,
) -> PyResult<omnimvs_data::OpenOptions> {
    let frame = match rig_frame {
        None | Some("calibration") => omnimvs_camera::FrameChoice::Calibration,
        Some("fitted") => omnimvs_camera::FrameChoice::Fitted,
        Some(other) => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "rig_frame {other:?}: expected \"calibration\" or \"fitted\""
            )));
        }
    };
    Ok(omnimvs_data::OpenOptions {
        frame,
        min_depth_m: min_depth,
        ..Default::default()
    })
}

/// `omnimvs.KIND("PATH": N cameras, min depth D m)`, the `repr` of a dataset or a rig.
fn repr(kind: &str, path: &std::path::Path, dataset: &Dataset) -> String {
    format!(
        "omnimvs.{kind}({:?}: {} cameras, min depth {} m)",
        path.display().to_string(),
        dataset.rig.len(),
        dataset.config.min_depth_m
    )
}

/// Where a function's geometry comes from: a `Dataset` or a `Rig`.
pub fn geometry(source: &Bound<'_, PyAny>, name: &str) -> PyResult<Dataset> {
    if let Ok(ds) = source.cast::<PyDataset>() {
        return Ok(ds.get().inner.clone());
    }
    if let Ok(rig) = source.cast::<PyRig>() {
        return Ok(rig.get().inner.clone());
    }
    Err(bad_type(
        name,
        format!(
            "expected an omnimvs.Dataset or omnimvs.Rig, found {}",
            type_name(source)
        ),
    ))
}
