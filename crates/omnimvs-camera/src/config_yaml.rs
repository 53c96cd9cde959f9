//! Reader and writer for the reference `config.yaml` (the `cameras:` list).

use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use crate::{Camera, CameraError, CameraModel, OcamModel, Pose, Rig};

/// One entry of `cameras:` as written by the reference implementation.
#[derive(Debug, Deserialize)]
struct CameraEntry {
    cam_id: Option<u32>,
    img_dir: Option<String>,
    model: Option<String>,
    poly: Vec<f64>,
    inv_poly: Vec<f64>,
    center: [f64; 2],
    affine: [f64; 3],
    image_size: [u32; 2],
    invalid_mask: Option<String>,
    pose: [f64; 6],
    max_fov: f64,
}

#[derive(Debug, Deserialize)]
struct CamerasSection {
    cameras: Vec<CameraEntry>,
}

/// Reads the rig from a reference `config.yaml`.
///
/// # Errors
/// [`CameraError`] naming the file and the field: unreadable file, invalid
/// YAML, a missing or non-numeric field, a polynomial whose leading count
/// disagrees with its coefficients, an unknown camera model, a non-positive
/// image size or field of view.
pub fn read_config_rig(path: &Path) -> Result<Rig, CameraError> {
    let text = std::fs::read_to_string(path).map_err(|source| CameraError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_config_rig(path, &text)
}

/// Parses the rig from the text of a `config.yaml`; `path` is used in errors.
///
/// # Errors
/// As [`read_config_rig`].
pub fn parse_config_rig(path: &Path, text: &str) -> Result<Rig, CameraError> {
    let value = crate::yaml::parse_yaml(path, text)?;
    let section: CamerasSection = crate::yaml::from_value(path, value)?;
    if section.cameras.is_empty() {
        return Err(CameraError::field(
            path,
            "cameras",
            "expected at least one camera, found an empty list",
        ));
    }
    let cameras = section
        .cameras
        .into_iter()
        .enumerate()
        .map(|(i, entry)| camera_from_entry(path, i, entry))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Rig::new(cameras))
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

fn camera_from_entry(path: &Path, index: usize, entry: CameraEntry) -> Result<Camera, CameraError> {
    let prefix = format!("cameras[{index}].");
    let model_name = entry.model.as_deref().unwrap_or("ocam");
    if model_name != "ocam" {
        return Err(CameraError::field(
            path,
            format!("{prefix}model"),
            format!("unknown camera model {model_name:?}, expected \"ocam\""),
        ));
    }
    let poly = split_counted_poly(path, &format!("{prefix}poly"), &entry.poly)?;
    let inv_poly = split_counted_poly(path, &format!("{prefix}inv_poly"), &entry.inv_poly)?;
    let [center_row, center_col] = entry.center;
    let [c, d, e] = entry.affine;
    let [height, width] = entry.image_size;
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
    if entry.pose.iter().any(|v| !v.is_finite()) {
        return Err(CameraError::field(
            path,
            format!("{prefix}pose"),
            "expected six finite numbers",
        ));
    }
    let [rx, ry, rz, tx, ty, tz] = entry.pose;
    let id = entry.cam_id.unwrap_or(index as u32 + 1);
    let img_dir = entry.img_dir.unwrap_or_else(|| format!("cam{id}"));
    Ok(Camera::new(
        id,
        img_dir,
        CameraModel::Ocam(model),
        Pose {
            rvec: [rx, ry, rz],
            t_m: [tx, ty, tz],
        },
        entry.invalid_mask,
    ))
}

/// The `cameras:` section of a reference `config.yaml` for `rig`, the inverse
/// of [`parse_config_rig`]: numbers are written at full precision, so reading
/// the text back gives the same rig bit for bit.
pub fn config_cameras_yaml(rig: &Rig) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "cameras:");
    for cam in &rig.cameras {
        let CameraModel::Ocam(m) = &cam.model;
        let mut poly = vec![m.poly.len() as f64];
        poly.extend(&m.poly);
        let mut inv = vec![m.inv_poly.len() as f64];
        inv.extend(&m.inv_poly);
        let _ = writeln!(s, "  - cam_id: {}", cam.id);
        let _ = writeln!(s, "    img_dir: {:?}", cam.img_dir);
        let _ = writeln!(s, "    model: ocam");
        let _ = writeln!(s, "    poly: {}", list(&poly));
        let _ = writeln!(s, "    inv_poly: {}", list(&inv));
        let _ = writeln!(s, "    center: {}", list(&[m.center_row, m.center_col]));
        let _ = writeln!(s, "    affine: {}", list(&[m.c, m.d, m.e]));
        let _ = writeln!(s, "    image_size: [{}, {}]", m.height, m.width);
        if let Some(mask) = &cam.invalid_mask {
            let _ = writeln!(s, "    invalid_mask: {mask:?}");
        }
        let _ = writeln!(s, "    pose: {}", list(&cam.pose.to_array()));
        let _ = writeln!(s, "    max_fov: {:?}", m.max_fov_deg);
    }
    s
}

fn list(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
    format!("[{}]", items.join(", "))
}
