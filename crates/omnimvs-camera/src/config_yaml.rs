//! The one reader and writer of the reference `config.yaml`: every section, typed
//! ([`ConfigFile`]). This crate turns `cameras:` into a [`Rig`]; the dataset crate reads
//! `config:` and `dataset:` from the same parse.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_saphyr::{DoubleQuoted, FlowSeq};

use crate::{Camera, CameraError, CameraModel, OcamModel, Pose, Rig};

/// One entry of `cameras:` of a reference `config.yaml`, read by [`parse_config_rig`] and
/// written by [`config_cameras_yaml`] (lists in flow style and folder names quoted, as the
/// reference writes them; the wrappers are transparent when reading).
#[derive(Debug, Serialize, Deserialize)]
pub struct ConfigCamera {
    cam_id: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    img_dir: Option<DoubleQuoted<String>>,
    model: Option<String>,
    /// `[count, a0, a1, ...]`.
    poly: FlowSeq<Vec<f64>>,
    /// `[count, a0, a1, ...]`.
    inv_poly: FlowSeq<Vec<f64>>,
    /// `[row, col]`.
    center: FlowSeq<[f64; 2]>,
    /// `[c, d, e]`.
    affine: FlowSeq<[f64; 3]>,
    /// `[height, width]`.
    image_size: FlowSeq<[u32; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    invalid_mask: Option<DoubleQuoted<String>>,
    /// `[rx, ry, rz, tx, ty, tz]`.
    pose: FlowSeq<[f64; 6]>,
    /// Degrees.
    max_fov: f64,
}

impl ConfigCamera {
    /// The entry of `cam`: every number at full precision, so that reading it back gives
    /// the same camera bit for bit.
    pub fn of(cam: &Camera) -> Self {
        let CameraModel::Ocam(m) = &cam.model;
        let counted = |coeffs: &[f64]| {
            let mut v = vec![coeffs.len() as f64];
            v.extend(coeffs);
            FlowSeq(v)
        };
        Self {
            cam_id: Some(cam.id),
            img_dir: Some(DoubleQuoted(cam.img_dir.clone())),
            model: Some("ocam".into()),
            poly: counted(&m.poly),
            inv_poly: counted(&m.inv_poly),
            center: FlowSeq([m.center_row, m.center_col]),
            affine: FlowSeq([m.c, m.d, m.e]),
            image_size: FlowSeq([m.height, m.width]),
            invalid_mask: cam.invalid_mask.clone().map(DoubleQuoted),
            pose: FlowSeq(cam.pose.to_array()),
            max_fov: m.max_fov_deg,
        }
    }

    /// The entries of every camera of `rig`, in order.
    pub fn of_rig(rig: &Rig) -> Vec<Self> {
        rig.cameras.iter().map(Self::of).collect()
    }
}

/// A reference `config.yaml`, every section of it, as one parse reads it and the writer
/// writes it (sections in the reference's order: `config`, `dataset`, `cameras`).
#[derive(Debug, Serialize, Deserialize)]
pub struct ConfigFile {
    /// `config:`, the sweep's settings.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub config: Option<SweepSection>,
    /// `dataset:`, where the images and ground truth are and the frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dataset: Option<DatasetSection>,
    /// `cameras:`, the rig.
    pub cameras: Vec<ConfigCamera>,
}

/// The `config:` section.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepSection {
    /// The sweep's minimum depth, metres.
    pub omnimvs_sweep_min_depth: f64,
}

/// The `dataset:` section as written (patterns quoted, index lists in flow style; the
/// wrappers are transparent when reading). The dataset crate checks and interprets it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DatasetSection {
    /// printf pattern of an image by camera and frame, e.g. `cam%d/%05d.png`.
    pub img_fmt: DoubleQuoted<String>,
    /// printf pattern of a ground-truth file by frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gt_fmt: Option<DoubleQuoted<String>>,
    pub start: Option<u32>,
    pub step: Option<u32>,
    pub end: Option<u32>,
    /// `gt` where the reference should load ground truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dtype: Option<String>,
    /// Latitude range of the ground truth, degrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gt_phi: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub train_idx: Option<FlowSeq<Vec<u32>>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub test_idx: Option<FlowSeq<Vec<u32>>>,
}

impl ConfigFile {
    /// Reads a `config.yaml`.
    ///
    /// # Errors
    /// [`CameraError`] naming the file and the field: unreadable file, invalid YAML, a
    /// field missing or of the wrong type.
    pub fn read(path: &Path) -> Result<Self, CameraError> {
        let text = std::fs::read_to_string(path).map_err(|source| CameraError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(path, &text)
    }

    /// Parses the text of a `config.yaml`; `path` is used in errors.
    ///
    /// # Errors
    /// As [`Self::read`].
    pub fn parse(path: &Path, text: &str) -> Result<Self, CameraError> {
        let value = omnimvs_core::yaml::parse_yaml(path, text)?;
        Ok(omnimvs_core::yaml::from_value(path, value)?)
    }

    /// The file with the cameras of `rig` and no other section.
    pub fn of_rig(rig: &Rig) -> Self {
        Self {
            config: None,
            dataset: None,
            cameras: ConfigCamera::of_rig(rig),
        }
    }

    /// The rig of `cameras:`; `path` is used in errors.
    ///
    /// # Errors
    /// [`CameraError`] naming the field: an empty list, a polynomial whose leading count
    /// disagrees with its coefficients, an unknown camera model, a non-positive image size or
    /// field of view.
    pub fn rig(&self, path: &Path) -> Result<Rig, CameraError> {
        if self.cameras.is_empty() {
            return Err(CameraError::field(
                path,
                "cameras",
                "expected at least one camera, found an empty list",
            ));
        }
        let cameras = self
            .cameras
            .iter()
            .enumerate()
            .map(|(i, entry)| camera_from_entry(path, i, entry))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Rig::new(cameras))
    }

    /// The text of the file: block-style YAML with the reference's layout, numbers at full
    /// precision (reading it back gives the same values bit for bit).
    ///
    /// # Errors
    /// [`CameraError::Yaml`] if the serialiser fails (it does not for a valid rig).
    pub fn to_yaml(&self) -> Result<String, CameraError> {
        Ok(omnimvs_core::yaml::to_yaml("a config.yaml", self)?)
    }
}

/// Reads the rig from a reference `config.yaml`.
///
/// # Errors
/// [`CameraError`] naming the file and the field: unreadable file, invalid
/// YAML, a missing or non-numeric field, a polynomial whose leading count
/// disagrees with its coefficients, an unknown camera model, a non-positive
/// image size or field of view.
pub fn read_config_rig(path: &Path) -> Result<Rig, CameraError> {
    ConfigFile::read(path)?.rig(path)
}

/// Parses the rig from the text of a `config.yaml`; `path` is used in errors.
///
/// # Errors
/// As [`read_config_rig`].
pub fn parse_config_rig(path: &Path, text: &str) -> Result<Rig, CameraError> {
    ConfigFile::parse(path, text)?.rig(path)
}

/// Splits a `[count, a0, a1, ...]` polynomial and checks the count.
pub(crate) fn split_counted_poly(
    path: &Path,
    field: &str,
    values: &[f64],
) -> Result<Vec<f64>, CameraError> {
    let Some((&count, coeffs)) = values.split_first() else {
        return Err(CameraError::field(
            path,
            field,
            "expected [count, a0, a1, ...], found an empty list",
        ));
    };
    if count.fract() != 0.0 || count < 1.0 {
        return Err(CameraError::field(
            path,
            field,
            format!("expected a positive whole coefficient count first, found {count}"),
        ));
    }
    if count as usize != coeffs.len() {
        return Err(CameraError::field(
            path,
            field,
            format!(
                "the leading count says {count} coefficients but {} follow",
                coeffs.len()
            ),
        ));
    }
    if let Some(bad) = coeffs.iter().find(|a| !a.is_finite()) {
        return Err(CameraError::field(
            path,
            field,
            format!("expected finite coefficients, found {bad}"),
        ));
    }
    Ok(coeffs.to_vec())
}

/// Checks the parts of an OCamCalib model that would make projection
/// meaningless (zero-size image, singular affine matrix, bad FOV).
pub(crate) fn validate_ocam(path: &Path, prefix: &str, m: &OcamModel) -> Result<(), CameraError> {
    if m.width == 0 || m.height == 0 {
        return Err(CameraError::field(
            path,
            format!("{prefix}image_size"),
            format!(
                "expected a positive [height, width], found [{}, {}]",
                m.height, m.width
            ),
        ));
    }
    if (m.c - m.d * m.e).abs() < 1e-12 {
        return Err(CameraError::field(
            path,
            format!("{prefix}affine"),
            "expected an invertible affine matrix (c - d*e != 0)",
        ));
    }
    if !(m.max_fov_deg > 0.0 && m.max_fov_deg <= 360.0) {
        return Err(CameraError::field(
            path,
            format!("{prefix}max_fov"),
            format!("expected degrees in (0, 360], found {}", m.max_fov_deg),
        ));
    }
    let all = [m.center_row, m.center_col, m.c, m.d, m.e];
    if all.iter().any(|v| !v.is_finite()) {
        return Err(CameraError::field(
            path,
            format!("{prefix}center/affine"),
            "expected finite numbers",
        ));
    }
    Ok(())
}

fn camera_from_entry(
    path: &Path,
    index: usize,
    entry: &ConfigCamera,
) -> Result<Camera, CameraError> {
    let prefix = format!("cameras[{index}].");
    let model_name = entry.model.as_deref().unwrap_or("ocam");
    if model_name != "ocam" {
        return Err(CameraError::field(
            path,
            format!("{prefix}model"),
            format!("unknown camera model {model_name:?}, expected \"ocam\""),
        ));
    }
    let poly = split_counted_poly(path, &format!("{prefix}poly"), &entry.poly.0)?;
    let inv_poly = split_counted_poly(path, &format!("{prefix}inv_poly"), &entry.inv_poly.0)?;
    let [center_row, center_col] = entry.center.0;
    let [c, d, e] = entry.affine.0;
    let [height, width] = entry.image_size.0;
    let model = OcamModel {
        poly,
        inv_poly,
        center_row,
        center_col,
        c,
        d,
        e,
        width,
        height,
        max_fov_deg: entry.max_fov,
    };
    validate_ocam(path, &prefix, &model)?;
    if entry.pose.0.iter().any(|v| !v.is_finite()) {
        return Err(CameraError::field(
            path,
            format!("{prefix}pose"),
            "expected six finite numbers",
        ));
    }
    let [rx, ry, rz, tx, ty, tz] = entry.pose.0;
    let id = entry.cam_id.unwrap_or(index as u32 + 1);
    let img_dir = entry
        .img_dir
        .as_ref()
        .map_or_else(|| format!("cam{id}"), |dir| dir.0.clone());
    Ok(Camera::new(
        id,
        img_dir,
        CameraModel::Ocam(model),
        Pose {
            rvec: [rx, ry, rz],
            t_m: [tx, ty, tz],
        },
        entry.invalid_mask.as_ref().map(|mask| mask.0.clone()),
    ))
}

/// The `cameras:` section of a reference `config.yaml` for `rig`, the inverse
/// of [`parse_config_rig`]: numbers are written at full precision, so reading
/// the text back gives the same rig bit for bit.
///
/// # Errors
/// [`CameraError::Yaml`] if the serialiser fails (it does not for a valid rig).
pub fn config_cameras_yaml(rig: &Rig) -> Result<String, CameraError> {
    ConfigFile::of_rig(rig).to_yaml()
}
