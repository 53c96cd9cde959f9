//! The calibration-file formats a rig is read from and written to, told apart by the path:
//! the reference `config.yaml`, the released `ocamN.txt` + `poses.txt`, Basalt's
//! `calibration.json` and Kalibr's `camchain.yaml`.

use std::path::{Path, PathBuf};

use crate::{
    CameraError, LengthUnit, Rig, basalt_calibration_json, config_cameras_yaml,
    kalibr_camchain_yaml, read_basalt_calibration, read_config_rig, read_kalibr_camchain,
    read_ocam_txt_rig_in, write_ocam_txt_rig,
};

/// The released folders' field of view, degrees (`ocamN.txt` does not carry one).
const OCAM_TXT_MAX_FOV_DEG: f64 = 220.0;

/// A calibration-file format of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigFormat {
    /// The reference `config.yaml` (`cameras:`).
    ConfigYaml,
    /// The released datasets' folder of `ocam1.txt`, `ocam2.txt`, ... and `poses.txt`
    /// (centimetres, 220 degrees field of view).
    OcamTxt,
    /// Basalt's `calibration.json`.
    Basalt,
    /// Kalibr's `camchain.yaml`.
    Kalibr,
}

impl RigFormat {
    /// The format's short name: `config.yaml`, `ocam-txt`, `basalt` or `kalibr`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::ConfigYaml => "config.yaml",
            Self::OcamTxt => "ocam-txt",
            Self::Basalt => "basalt",
            Self::Kalibr => "kalibr",
        }
    }

    /// The frame the format's poses are expressed in, as a phrase.
    pub fn rig_frame(&self) -> &'static str {
        match self {
            Self::ConfigYaml => "the rig frame of config.yaml",
            Self::OcamTxt => "the frame of poses.txt",
            Self::Basalt => "Basalt's IMU frame (T_imu_cam)",
            Self::Kalibr => "cam0's frame (Kalibr)",
        }
    }

    /// The file name the format has in a folder (for `ocam-txt`, the first camera's file).
    fn file_name(&self) -> &'static str {
        match self {
            Self::ConfigYaml => "config.yaml",
            Self::OcamTxt => "ocam1.txt",
            Self::Basalt => "calibration.json",
            Self::Kalibr => "camchain.yaml",
        }
    }

    /// The format of the calibration at `path`. A folder: `config.yaml` inside it, else
    /// `calibration.json`, else `camchain.yaml` or another `*camchain*.yaml` (the first by
    /// name), else `ocam1.txt`. A file: `.json` is Basalt's; `.yaml` or `.yml` is read and told
    /// by its top-level keys (`cameras`: config.yaml, `cam0`: Kalibr); `.txt` is a file of the
    /// released layout, read from its folder.
    ///
    /// # Errors
    /// [`CameraError::Io`] for a path that does not exist or cannot be read;
    /// [`CameraError::Field`] naming the path when no format fits.
    pub fn detect(path: &Path) -> Result<Self, CameraError> {
        locate(path).map(|(format, _)| format)
    }
}

/// The format at `path` and the file to read (for `ocam-txt`, the folder).
fn locate(path: &Path) -> Result<(RigFormat, PathBuf), CameraError> {
    let io = |source| CameraError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        for format in [RigFormat::ConfigYaml, RigFormat::Basalt, RigFormat::Kalibr] {
            let file = path.join(format.file_name());
            if file.is_file() {
                return Ok((format, file));
            }
        }
        let mut camchains: Vec<PathBuf> = std::fs::read_dir(path)
            .map_err(io)?
            .filter_map(|entry| entry.ok().map(|e| e.path()))
            .filter(|p| {
                let name = p.file_name().map(|n| n.to_string_lossy().into_owned());
                p.is_file() && name.is_some_and(|n| n.contains("camchain") && n.ends_with(".yaml"))
            })
            .collect();
        camchains.sort();
        if let Some(first) = camchains.into_iter().next() {
            return Ok((RigFormat::Kalibr, first));
        }
        if path.join("ocam1.txt").is_file() {
            return Ok((RigFormat::OcamTxt, path.to_path_buf()));
        }
        return Err(CameraError::field(
            path,
            "(folder)",
            "expected a calibration inside: config.yaml, calibration.json (Basalt), \
             camchain.yaml or *camchain*.yaml (Kalibr), or ocam1.txt + poses.txt",
        ));
    }
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("json") => Ok((RigFormat::Basalt, path.to_path_buf())),
        Some("yaml" | "yml") => Ok((yaml_format(path)?, path.to_path_buf())),
        Some("txt") => {
            let dir = path.parent().unwrap_or(Path::new("."));
            let dir = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            Ok((RigFormat::OcamTxt, dir.to_path_buf()))
        }
        _ => Err(CameraError::field(
            path,
            "(file name)",
            "expected a calibration file ending in .json (Basalt), .yaml or .yml \
             (config.yaml or Kalibr), or .txt (ocamN.txt), or a folder holding one",
        )),
    }
}

/// config.yaml or Kalibr, by the top-level keys of a YAML file.
fn yaml_format(path: &Path) -> Result<RigFormat, CameraError> {
    let text = std::fs::read_to_string(path).map_err(|source| CameraError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let value = omnimvs_core::yaml::parse_yaml(path, &text)?;
    let has = |key: &str| value.as_object().is_some_and(|m| m.contains_key(key));
    if has("cameras") {
        Ok(RigFormat::ConfigYaml)
    } else if has("cam0") {
        Ok(RigFormat::Kalibr)
    } else {
        Err(CameraError::field(
            path,
            "(top level)",
            "expected `cameras` (config.yaml) or `cam0` (Kalibr's camchain.yaml)",
        ))
    }
}

/// Reads the rig at `path` (a file, or a folder holding one; see [`RigFormat::detect`]) and
/// returns it with its format and the file read (for `ocam-txt`, the folder). Poses are in
/// the format's frame ([`RigFormat::rig_frame`]).
///
/// # Errors
/// As [`RigFormat::detect`], then as the format's reader.
pub fn read_rig_file(path: &Path) -> Result<(Rig, RigFormat, PathBuf), CameraError> {
    let (format, file) = locate(path)?;
    let rig = match format {
        RigFormat::ConfigYaml => read_config_rig(&file)?,
        RigFormat::OcamTxt => {
            read_ocam_txt_rig_in(&file, OCAM_TXT_MAX_FOV_DEG, LengthUnit::Centimetre)?
        }
        RigFormat::Basalt => read_basalt_calibration(&file)?,
        RigFormat::Kalibr => read_kalibr_camchain(&file)?,
    };
    match format {
        RigFormat::Basalt => rig.check_cameras_see(&file, |i| format!("value0.intrinsics[{i}]"))?,
        RigFormat::Kalibr => rig.check_cameras_see(&file, |i| format!("cam{i}"))?,
        // config.yaml is checked by its reader; the released files' cameras by their number.
        RigFormat::ConfigYaml => {}
        RigFormat::OcamTxt => rig.check_cameras_see(&file, |i| format!("ocam{}.txt", i + 1))?,
    }
    Ok((rig, format, file))
}

/// Writes `rig` in `format` at `out`, atomically. `ocam-txt` writes its files into the folder
/// `out` (created if missing); the other formats write the file `out`, or their usual file
/// name (`config.yaml`, `calibration.json`, `camchain.yaml`) inside `out` when it is an
/// existing folder. config.yaml holds the `cameras:` section only.
///
/// # Errors
/// The format writer's refusal of a camera it cannot state, or [`CameraError::Io`] naming the
/// file that cannot be written.
pub fn write_rig_file(rig: &Rig, format: RigFormat, out: &Path) -> Result<(), CameraError> {
    let text = match format {
        RigFormat::OcamTxt => {
            std::fs::create_dir_all(out).map_err(|source| CameraError::Io {
                path: out.to_path_buf(),
                source,
            })?;
            return write_ocam_txt_rig(rig, out);
        }
        RigFormat::ConfigYaml => config_cameras_yaml(rig)?,
        RigFormat::Basalt => basalt_calibration_json(rig)?,
        RigFormat::Kalibr => kalibr_camchain_yaml(rig)?,
    };
    let file = if out.is_dir() {
        out.join(format.file_name())
    } else {
        out.to_path_buf()
    };
    omnimvs_core::fs::write_atomic(&file, text.as_bytes())
        .map_err(|source| CameraError::Io { path: file, source })
}
