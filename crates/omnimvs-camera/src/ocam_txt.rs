//! Reader for the released datasets' calibration files: `ocam1.txt` ...
//! `ocamN.txt` (OCamCalib's `calib_results.txt` layout) and `poses.txt`
//! (`rx ry rz tx ty tz` per camera, camera-to-rig, translation in centimetres).

use std::path::Path;

use crate::config_yaml::{split_counted_poly, validate_ocam};
use crate::{Camera, CameraError, CameraModel, OcamModel, Pose, Rig};

/// The non-comment lines of a file, with their 1-based line numbers.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

fn parse_numbers(path: &Path, line: usize, text: &str) -> Result<Vec<f64>, CameraError> {
    text.split_whitespace()
        .map(|tok| {
            tok.parse::<f64>().map_err(|_| CameraError::Line {
                path: path.to_path_buf(),
                line,
                message: format!("expected a number, found {tok:?}"),
            })
        })
        .collect()
}

/// Parses one OCamCalib text file (five data lines: poly with its count,
/// inverse poly with its count, `xc yc`, `c d e`, `height width`).
///
/// # Errors
/// [`CameraError`] naming the file and the line or field.
pub fn parse_ocam_txt(path: &Path, text: &str, max_fov_deg: f64) -> Result<OcamModel, CameraError> {
    let lines: Vec<(usize, &str)> = data_lines(text).collect();
    const FIELDS: [&str; 5] = [
        "poly",
        "inv_poly",
        "center (xc yc)",
        "affine (c d e)",
        "image size (height width)",
    ];
    if lines.len() < FIELDS.len() {
        return Err(CameraError::field(
            path,
            FIELDS[lines.len()],
            format!(
                "expected 5 data lines (poly, inv_poly, xc yc, c d e, height width), found {}",
                lines.len()
            ),
        ));
    }
    let mut rows = Vec::with_capacity(5);
    for &(line, text) in &lines[..5] {
        rows.push(parse_numbers(path, line, text)?);
    }
    let expect_len = |k: usize, n: usize| -> Result<(), CameraError> {
        if rows[k].len() == n {
            Ok(())
        } else {
            Err(CameraError::Line {
                path: path.to_path_buf(),
                line: lines[k].0,
                message: format!(
                    "{}: expected {n} numbers, found {}",
                    FIELDS[k],
                    rows[k].len()
                ),
            })
        }
    };
    expect_len(2, 2)?;
    expect_len(3, 3)?;
    expect_len(4, 2)?;
    let poly = split_counted_poly(path, "poly", &rows[0])?;
    let inv_poly = split_counted_poly(path, "inv_poly", &rows[1])?;
    let size = &rows[4];
    if size.iter().any(|v| v.fract() != 0.0 || *v < 1.0) {
        return Err(CameraError::field(
            path,
            "image size",
            format!("expected positive whole numbers, found {size:?}"),
        ));
    }
    let model = OcamModel {
        poly,
        inv_poly,
        center_row: rows[2][0],
        center_col: rows[2][1],
        c: rows[3][0],
        d: rows[3][1],
        e: rows[3][2],
        height: size[0] as u32,
        width: size[1] as u32,
        max_fov_deg,
    };
    validate_ocam(path, "", &model)?;
    Ok(model)
}

/// The unit of the translations in a `poses.txt`: centimetres in the released OmniMVS
/// datasets (OmniThings, OmniHouse, the urban sets), millimetres in SweepNet's
/// `real_indoor_sample`. Rotations are always radians.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LengthUnit {
    /// Metres.
    Metre,
    /// Centimetres, the released datasets' unit.
    #[default]
    Centimetre,
    /// Millimetres.
    Millimetre,
}

impl LengthUnit {
    /// Units per metre (a division by it converts to metres exactly as `/ 100.0` did).
    pub fn per_metre(self) -> f64 {
        match self {
            Self::Metre => 1.0,
            Self::Centimetre => 100.0,
            Self::Millimetre => 1000.0,
        }
    }

    /// The unit's symbol: `m`, `cm` or `mm`.
    pub fn symbol(self) -> &'static str {
        match self {
            Self::Metre => "m",
            Self::Centimetre => "cm",
            Self::Millimetre => "mm",
        }
    }
}

/// Reads `m`, `cm` or `mm`; the error names the three.
impl std::str::FromStr for LengthUnit {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "m" => Ok(Self::Metre),
            "cm" => Ok(Self::Centimetre),
            "mm" => Ok(Self::Millimetre),
            other => Err(format!(
                "expected a length unit m, cm or mm, found {other:?}"
            )),
        }
    }
}

impl std::fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.symbol())
    }
}

/// Reads a rig from a released dataset's folder: `ocam1.txt`, `ocam2.txt`, ...
/// (as many as exist, consecutively) and `poses.txt` with one line per camera.
/// Poses are converted from centimetres to metres (see [`read_ocam_txt_rig_in`] for
/// another unit). Every camera gets `max_fov_deg` (the text files do not carry it) and
/// `img_dir = camK`.
///
/// # Errors
/// [`CameraError`] naming the file: no `ocam1.txt`, a malformed file, or a
/// `poses.txt` whose line count differs from the number of `ocamK.txt` files.
pub fn read_ocam_txt_rig(dir: &Path, max_fov_deg: f64) -> Result<Rig, CameraError> {
    read_ocam_txt_rig_in(dir, max_fov_deg, LengthUnit::Centimetre)
}

/// [`read_ocam_txt_rig`] with the translations of `poses.txt` in `pose_unit`.
///
/// # Errors
/// As [`read_ocam_txt_rig`].
pub fn read_ocam_txt_rig_in(
    dir: &Path,
    max_fov_deg: f64,
    pose_unit: LengthUnit,
) -> Result<Rig, CameraError> {
    let read = |path: &Path| {
        std::fs::read_to_string(path).map_err(|source| CameraError::Io {
            path: path.to_path_buf(),
            source,
        })
    };
    let mut models = Vec::new();
    loop {
        let path = dir.join(format!("ocam{}.txt", models.len() + 1));
        if !path.exists() {
            break;
        }
        models.push(parse_ocam_txt(&path, &read(&path)?, max_fov_deg)?);
    }
    if models.is_empty() {
        let path = dir.join("ocam1.txt");
        return Err(CameraError::Io {
            path,
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no ocam1.txt calibration file",
            ),
        });
    }
    let poses_path = dir.join("poses.txt");
    let poses_text = read(&poses_path)?;
    let mut poses = Vec::new();
    for (line, text) in data_lines(&poses_text) {
        let v = parse_numbers(&poses_path, line, text)?;
        if v.len() != 6 {
            return Err(CameraError::Line {
                path: poses_path,
                line,
                message: format!(
                    "expected 6 numbers (rx ry rz tx ty tz, {pose_unit}), found {}",
                    v.len()
                ),
            });
        }
        poses.push(Pose {
            rvec: [v[0], v[1], v[2]],
            t_m: [v[3], v[4], v[5]].map(|t| t / pose_unit.per_metre()),
        });
    }
    if poses.len() != models.len() {
        return Err(CameraError::field(
            &poses_path,
            "poses",
            format!(
                "expected one pose per camera ({} ocamK.txt files), found {} lines",
                models.len(),
                poses.len()
            ),
        ));
    }
    let cameras = models
        .into_iter()
        .zip(poses)
        .enumerate()
        .map(|(i, (model, pose))| {
            let id = i as u32 + 1;
            Camera::new(id, format!("cam{id}"), CameraModel::Ocam(model), pose, None)
        })
        .collect();
    Ok(Rig::new(cameras))
}
/// Writes `rig` in the released datasets' layout into `dir`: `ocam1.txt`, `ocam2.txt`, ...
/// (OCamCalib's text form) and `poses.txt` (camera-to-rig, translation in centimetres), each
/// file atomically. [`read_ocam_txt_rig`] reads them back as the same rig (up to the last bit
/// of the centimetre conversion).
///
/// # Errors
/// [`CameraError::Io`] naming a file that cannot be written.
pub fn write_ocam_txt_rig(rig: &Rig, dir: &Path) -> Result<(), CameraError> {
    let write = |name: String, text: String| {
        let path = dir.join(name);
        omnimvs_core::fs::write_atomic(&path, text.as_bytes())
            .map_err(|source| CameraError::Io { path, source })
    };
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:e}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    // Every camera is checked before any file is written.
    if let Some((i, cam)) =
        (rig.cameras.iter().enumerate()).find(|(_, cam)| !matches!(cam.model, CameraModel::Ocam(_)))
    {
        return Err(CameraError::field(
            dir.join(format!("ocam{}.txt", i + 1)),
            "model",
            format!(
                "the released layout holds OCamCalib models only; camera {} is {}",
                i + 1,
                cam.model.name()
            ),
        ));
    }
    let mut poses = String::from("# rx ry rz tx ty tz (camera to rig; rad, cm)\n");
    for (i, cam) in rig.cameras.iter().enumerate() {
        let CameraModel::Ocam(m) = &cam.model else {
            continue; // refused above
        };
        let text = format!(
            "#polynomial coefficients for the DIRECT mapping function\n\n{} {}\n\n\
             #polynomial coefficients for the inverse mapping function\n\n{} {}\n\n\
             #center: \"row\" and \"column\"\n\n{:e} {:e}\n\n#affine parameters\n\n{:e} {:e} {:e}\n\n\
             #image size: \"height\" and \"width\"\n\n{} {}\n",
            m.poly.len(),
            join(&m.poly),
            m.inv_poly.len(),
            join(&m.inv_poly),
            m.center_row,
            m.center_col,
            m.c,
            m.d,
            m.e,
            m.height,
            m.width
        );
        write(format!("ocam{}.txt", i + 1), text)?;
        let [rx, ry, rz, tx, ty, tz] = cam.pose.to_array();
        poses += &format!(
            "{rx:e} {ry:e} {rz:e} {:e} {:e} {:e}\n",
            tx * 100.0,
            ty * 100.0,
            tz * 100.0
        );
    }
    write("poses.txt".into(), poses)
}
