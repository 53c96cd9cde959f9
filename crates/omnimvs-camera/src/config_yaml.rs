//! The one reader and writer of the reference `config.yaml`: every section, typed
//! ([`ConfigFile`]). This crate turns `cameras:` into a [`Rig`]; the dataset crate reads
//! `config:` and `dataset:` from the same parse.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_saphyr::{DoubleQuoted, FlowSeq};

use crate::{
    Camera, CameraError, CameraModel, CentralCamera, DoubleSphere, ExtendedUnified, KannalaBrandt4,
    Lens, OcamModel, PinholeRadtan, Pose, Rig, Unified,
};

/// One entry of `cameras:` of a reference `config.yaml`, read by [`parse_config_rig`] and
/// written by [`config_cameras_yaml`] (lists in flow style and folder names quoted, as the
/// reference writes them; the wrappers are transparent when reading).
#[derive(Debug, Serialize, Deserialize)]
pub struct ConfigCamera {
    cam_id: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    img_dir: Option<DoubleQuoted<String>>,
    model: Option<String>,
    /// OCamCalib: `[count, a0, a1, ...]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    poly: Option<FlowSeq<Vec<f64>>>,
    /// OCamCalib: `[count, a0, a1, ...]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    inv_poly: Option<FlowSeq<Vec<f64>>>,
    /// OCamCalib: `[row, col]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    center: Option<FlowSeq<[f64; 2]>>,
    /// OCamCalib: `[c, d, e]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    affine: Option<FlowSeq<[f64; 3]>>,
    /// The closed-form models: `[fx, fy, cx, cy]` then the model's own parameters (`ds`:
    /// `xi, alpha`; `eucm`: `alpha, beta`; `ucm`: `xi`; `kb4` and `pinhole-radtan`: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    intrinsics: Option<FlowSeq<Vec<f64>>>,
    /// `kb4`: `[k1, k2, k3, k4]`; `ucm` (optional) and `pinhole-radtan`: `[k1, k2, p1, p2]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    distortion: Option<FlowSeq<Vec<f64>>>,
    /// `[height, width]`.
    image_size: FlowSeq<[u32; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    invalid_mask: Option<DoubleQuoted<String>>,
    /// `[rx, ry, rz, tx, ty, tz]`.
    pose: FlowSeq<[f64; 6]>,
    /// Degrees (OCamCalib: required; the closed-form models: the model's widest if absent).
    #[serde(skip_serializing_if = "Option::is_none")]
    max_fov: Option<f64>,
}

impl ConfigCamera {
    /// The entry of `cam`: every number at full precision, so that reading it back gives
    /// the same camera bit for bit.
    pub fn of(cam: &Camera) -> Self {
        let counted = |coeffs: &[f64]| {
            let mut v = vec![coeffs.len() as f64];
            v.extend(coeffs);
            FlowSeq(v)
        };
        let mut entry = Self {
            cam_id: Some(cam.id),
            img_dir: Some(DoubleQuoted(cam.img_dir.clone())),
            model: Some(cam.model.name().into()),
            poly: None,
            inv_poly: None,
            center: None,
            affine: None,
            intrinsics: None,
            distortion: None,
            image_size: FlowSeq([cam.model.height(), cam.model.width()]),
            invalid_mask: cam.invalid_mask.clone().map(DoubleQuoted),
            pose: FlowSeq(cam.pose.to_array()),
            max_fov: Some(cam.model.max_fov_deg()),
        };
        match &cam.model {
            CameraModel::Ocam(m) => {
                entry.poly = Some(counted(&m.poly));
                entry.inv_poly = Some(counted(&m.inv_poly));
                entry.center = Some(FlowSeq([m.center_row, m.center_col]));
                entry.affine = Some(FlowSeq([m.c, m.d, m.e]));
            }
            CameraModel::Central(c) => {
                let (intrinsics, distortion) = lens_parameters(&c.lens);
                entry.intrinsics = Some(FlowSeq(intrinsics));
                entry.distortion = distortion.map(FlowSeq);
            }
        }
        entry
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
        let rig = Rig::new(cameras);
        rig.check_cameras_see(path, |i| format!("cameras[{i}]"))?;
        Ok(rig)
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
    let model = if model_name == "ocam" {
        CameraModel::Ocam(ocam_from_entry(path, &prefix, entry)?)
    } else {
        CameraModel::Central(central_from_entry(path, &prefix, model_name, entry)?)
    };
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
        model,
        Pose {
            rvec: [rx, ry, rz],
            t_m: [tx, ty, tz],
        },
        entry.invalid_mask.as_ref().map(|mask| mask.0.clone()),
    ))
}

/// A field an entry of the model needs.
fn required<'a, T>(
    path: &Path,
    prefix: &str,
    field: &str,
    value: &'a Option<T>,
) -> Result<&'a T, CameraError> {
    value.as_ref().ok_or_else(|| {
        CameraError::field(
            path,
            format!("{prefix}{field}"),
            "missing: the model needs it",
        )
    })
}

/// The OCamCalib model of an entry.
fn ocam_from_entry(
    path: &Path,
    prefix: &str,
    entry: &ConfigCamera,
) -> Result<OcamModel, CameraError> {
    let poly = required(path, prefix, "poly", &entry.poly)?;
    let inv_poly = required(path, prefix, "inv_poly", &entry.inv_poly)?;
    let poly = split_counted_poly(path, &format!("{prefix}poly"), &poly.0)?;
    let inv_poly = split_counted_poly(path, &format!("{prefix}inv_poly"), &inv_poly.0)?;
    let [center_row, center_col] = required(path, prefix, "center", &entry.center)?.0;
    let [c, d, e] = required(path, prefix, "affine", &entry.affine)?.0;
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
        max_fov_deg: *required(path, prefix, "max_fov", &entry.max_fov)?,
    };
    validate_ocam(path, prefix, &model)?;
    Ok(model)
}

/// The closed-form camera of an entry (`model: ds | eucm | ucm | kb4 | pinhole-radtan`).
fn central_from_entry(
    path: &Path,
    prefix: &str,
    model_name: &str,
    entry: &ConfigCamera,
) -> Result<CentralCamera, CameraError> {
    let field =
        |name: &str, message: String| CameraError::field(path, format!("{prefix}{name}"), message);
    // A missing list reads as empty: the model's name is checked first, then the count.
    let intrinsics = entry
        .intrinsics
        .as_ref()
        .map_or(&[][..], |i| i.0.as_slice());
    let distortion = entry.distortion.as_ref().map(|d| d.0.as_slice());
    let lens = lens_from_parameters(model_name, intrinsics, distortion).map_err(|e| match e {
        LensError::Model => field(
            "model",
            format!(
                "unknown camera model {model_name:?}, expected \"ocam\", \"ds\", \"eucm\", \"ucm\", \"kb4\" or \"pinhole-radtan\""
            ),
        ),
        LensError::Count { field: name, want } => field(
            name,
            format!("expected {want} numbers for model {model_name:?}"),
        ),
        LensError::Param(e) => field("intrinsics", e.to_string()),
    })?;
    let [height, width] = entry.image_size.0;
    CentralCamera::new(lens, width, height, entry.max_fov)
}

/// Why the parameters of a closed-form lens could not be read.
enum LensError {
    /// An unknown model name.
    Model,
    /// A list of the wrong length.
    Count {
        field: &'static str,
        want: &'static str,
    },
    /// A parameter the model refuses.
    Param(CameraError),
}

/// The lens of `model` from its `intrinsics` (`[fx, fy, cx, cy, ...]`) and `distortion`.
fn lens_from_parameters(
    model: &str,
    intrinsics: &[f64],
    distortion: Option<&[f64]>,
) -> Result<Lens, LensError> {
    let count = |field, want: &'static str| LensError::Count { field, want };
    let four = |d: Option<&[f64]>, want| -> Result<Option<[f64; 4]>, LensError> {
        d.map(|d| <[f64; 4]>::try_from(d).map_err(|_| count("distortion", want)))
            .transpose()
    };
    let lens = match (model, intrinsics) {
        ("ds", &[fx, fy, cx, cy, xi, alpha]) => {
            DoubleSphere::new(fx, fy, cx, cy, xi, alpha).map(Lens::DoubleSphere)
        }
        ("eucm", &[fx, fy, cx, cy, alpha, beta]) => {
            ExtendedUnified::new(fx, fy, cx, cy, alpha, beta).map(Lens::ExtendedUnified)
        }
        ("ucm", &[fx, fy, cx, cy, xi]) => match four(distortion, "4 (k1, k2, p1, p2)")? {
            Some(k) => Unified::with_radtan(fx, fy, cx, cy, xi, k).map(Lens::Unified),
            None => Unified::new(fx, fy, cx, cy, xi).map(Lens::Unified),
        },
        ("kb4", &[fx, fy, cx, cy]) => {
            let k = four(distortion, "4 (k1, k2, k3, k4)")?
                .ok_or(count("distortion", "4 (k1, k2, k3, k4)"))?;
            let [k1, k2, k3, k4] = k;
            KannalaBrandt4::new(fx, fy, cx, cy, k1, k2, k3, k4).map(Lens::KannalaBrandt4)
        }
        ("pinhole-radtan", &[fx, fy, cx, cy]) => {
            let k = four(distortion, "4 (k1, k2, p1, p2)")?.unwrap_or([0.0; 4]);
            let [k1, k2, p1, p2] = k;
            PinholeRadtan::new(fx, fy, cx, cy, k1, k2, p1, p2).map(Lens::PinholeRadtan)
        }
        ("ds", _) => return Err(count("intrinsics", "6 (fx, fy, cx, cy, xi, alpha)")),
        ("eucm", _) => return Err(count("intrinsics", "6 (fx, fy, cx, cy, alpha, beta)")),
        ("ucm", _) => return Err(count("intrinsics", "5 (fx, fy, cx, cy, xi)")),
        ("kb4" | "pinhole-radtan", _) => return Err(count("intrinsics", "4 (fx, fy, cx, cy)")),
        _ => return Err(LensError::Model),
    };
    lens.map_err(LensError::Param)
}

/// A lens's `intrinsics` and `distortion` as [`lens_from_parameters`] reads them.
fn lens_parameters(lens: &Lens) -> (Vec<f64>, Option<Vec<f64>>) {
    let f = lens.focal();
    let mut intrinsics = vec![f.fx(), f.fy(), f.cx(), f.cy()];
    let distortion = match lens {
        Lens::DoubleSphere(m) => {
            intrinsics.extend([m.xi(), m.alpha()]);
            None
        }
        Lens::ExtendedUnified(m) => {
            intrinsics.extend([m.alpha(), m.beta()]);
            None
        }
        Lens::Unified(m) => {
            intrinsics.push(m.xi());
            Some(m.radtan().to_vec()).filter(|k| k.iter().any(|&v| v != 0.0))
        }
        Lens::KannalaBrandt4(m) => Some(m.k().to_vec()),
        Lens::PinholeRadtan(m) => Some(m.radtan().to_vec()),
    };
    (intrinsics, distortion)
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
