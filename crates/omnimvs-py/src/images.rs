//! numpy arrays to and from gray images, and the two ways a function gets a frame: a dataset
//! and a frame number, or the images themselves with a rig.

use numpy::{PyArray2, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use omnimvs_core::GrayImage;
use omnimvs_data::Dataset;
use pyo3::prelude::*;

use crate::arrays::{shape_text, type_name};
use crate::dataset::{PyDataset, PyRig, frame_number};
use crate::error::{IntoPyResult, bad_argument, bad_type};

/// Describes an array for messages: `uint8 array of shape (768, 800)`.
fn describe(obj: &Bound<'_, PyAny>) -> String {
    match obj.cast::<PyUntypedArray>() {
        Ok(a) => format!("{} array of shape {}", a.dtype(), shape_text(a.shape())),
        Err(_) => type_name(obj),
    }
}

/// One camera's image from a `numpy.uint8` array of shape `(height, width)`; `name` labels
/// errors (`images[2]`).
fn array_to_gray(
    obj: &Bound<'_, PyAny>,
    height: usize,
    width: usize,
    name: &str,
) -> PyResult<GrayImage> {
    let wrong = || {
        bad_argument(
            name,
            format!(
                "expected a numpy uint8 array of shape ({height}, {width}), found {}",
                describe(obj)
            ),
        )
    };
    let array = obj.cast::<PyArray2<u8>>().map_err(|_| wrong())?;
    if array.shape() != [height, width] {
        return Err(wrong());
    }
    let view = array.try_readonly().map_err(|e| bad_argument(name, e))?;
    let data: Vec<f32> = view.as_array().iter().map(|&v| f32::from(v)).collect();
    Ok(GrayImage {
        width,
        height,
        data,
    })
}

/// The images of one frame given as a sequence of arrays, one per camera of `rig`, each of
/// its camera's size.
fn arrays_to_frame(images: &Bound<'_, PyAny>, rig: &Dataset) -> PyResult<Vec<GrayImage>> {
    let cameras = &rig.rig.cameras;
    let items: Vec<Bound<'_, PyAny>> = match images.try_iter() {
        Ok(iter) if !images.is_instance_of::<pyo3::types::PyString>() => {
            iter.collect::<PyResult<_>>()?
        }
        _ => {
            return Err(bad_type(
                "images",
                format!(
                    "expected a Dataset or a list of numpy uint8 arrays (one per camera), found {}",
                    type_name(images)
                ),
            ));
        }
    };
    if items.len() != cameras.len() {
        return Err(bad_argument(
            "images",
            format!(
                "expected {} arrays, one per camera of {}, found {}",
                cameras.len(),
                rig.config_path.display(),
                items.len()
            ),
        ));
    }
    items
        .iter()
        .zip(cameras)
        .enumerate()
        .map(|(k, (item, camera))| {
            array_to_gray(
                item,
                camera.model.height() as usize,
                camera.model.width() as usize,
                &format!("images[{k}]"),
            )
        })
        .collect()
}

/// Where a frame's images come from.
pub enum FrameImages {
    /// Read from the dataset's files (inside the detached work).
    Dataset(u32),
    /// Given as arrays.
    Given(Vec<GrayImage>),
}

impl FrameImages {
    /// The gray images.
    ///
    /// # Errors
    /// A missing or unreadable image file.
    pub fn load(self, dataset: &Dataset) -> PyResult<Vec<GrayImage>> {
        match self {
            Self::Dataset(frame) => dataset.read_frame(frame).py_err(),
            Self::Given(images) => Ok(images),
        }
    }
}

/// The geometry and the images of `sgm`'s and `infer`'s first arguments: a `Dataset` and a
/// frame number, or a list of arrays and a `Rig`.
pub fn frame_source(
    source: &Bound<'_, PyAny>,
    frame: Option<i64>,
    rig: Option<&Bound<'_, PyRig>>,
) -> PyResult<(Dataset, FrameImages)> {
    if let Ok(ds) = source.cast::<PyDataset>() {
        if rig.is_some() {
            return Err(bad_argument(
                "rig",
                "not used with a Dataset (the dataset has its rig); pass images with a rig, or a dataset and a frame",
            ));
        }
        let frame = frame.ok_or_else(|| {
            bad_argument(
                "frame",
                "required with a Dataset (one of its frames, see Dataset.frames)",
            )
        })?;
        return Ok((
            ds.get().inner.clone(),
            FrameImages::Dataset(frame_number(frame)?),
        ));
    }
    let Some(rig) = rig else {
        return Err(bad_argument(
            "rig",
            format!(
                "required when images are given as arrays (omnimvs.Rig.from_config), found {} and no rig",
                describe(source)
            ),
        ));
    };
    if frame.is_some() {
        return Err(bad_argument(
            "frame",
            "only with a Dataset; images given as arrays are the frame",
        ));
    }
    let geometry = rig.get().inner.clone();
    let images = arrays_to_frame(source, &geometry)?;
    Ok((geometry, FrameImages::Given(images)))
}
