//! Basalt's `calibration.json` (its cereal JSON, `{"value0": {...}}`): read into a [`Rig`]
//! and written from one.
//!
//! The rig frame is Basalt's IMU frame: `T_imu_cam` maps a camera's points into it
//! (`X_imu = T_imu_cam X_cam`), so it is the camera's `rig_from_cam`. Camera `i` gets
//! `id = i` (0-based, as Basalt counts), `img_dir = cam{i}`, no invalid mask, and its lens
//! model's widest field of view (the file states none). Pixel positions follow the crate's
//! convention (0-based, centres at integers), as Basalt's do.
//!
//! | `camera_type` | parameters | model |
//! |---|---|---|
//! | `ds` | `fx fy cx cy xi alpha` | [`DoubleSphere`] |
//! | `eucm` | `fx fy cx cy alpha beta` | [`ExtendedUnified`] |
//! | `kb4` | `fx fy cx cy k1 k2 k3 k4` | [`KannalaBrandt4`] |
//! | `pinhole` | `fx fy cx cy` | [`PinholeRadtan`] without distortion |
//! | `ucm` | `fx fy cx cy alpha` | [`Unified`], re-parametrised (see below) |
//!
//! Basalt's unified model writes `m = (x, y) / (alpha d + (1 - alpha) z)`, `d = |p|`, where
//! ours (Mei's) writes `m = (x, y) / (z + xi d)`; dividing by `1 - alpha` gives
//! `xi = alpha / (1 - alpha)` and focal lengths `f / (1 - alpha)`, and back
//! `alpha = xi / (1 + xi)`, `f_basalt = f / (1 + xi)`.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Quaternion, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::interchange::{central_with_model_fov, param_in_field, unsupported};
use crate::{
    Camera, CameraError, CameraModel, CentralCamera, DoubleSphere, ExtendedUnified, KannalaBrandt4,
    Lens, PinholeRadtan, Pose, Rig, Unified,
};

/// The file name errors of the writer name.
const FILE: &str = "calibration.json";

/// The camera types the reader knows, as listed in its errors.
const SUPPORTED: &str = "\"ds\", \"eucm\", \"kb4\", \"pinhole\" or \"ucm\"";

/// The whole file: cereal wraps the calibration in `value0`.
#[derive(Serialize, Deserialize)]
struct BasaltFile {
    value0: BasaltCalibration,
}

/// `value0`: the cameras, and the IMU fields Basalt needs to load the file (written with
/// neutral values, ignored when reading).
#[derive(Serialize, Deserialize)]
struct BasaltCalibration {
    #[serde(rename = "T_imu_cam")]
    t_imu_cam: Vec<BasaltPose>,
    intrinsics: Vec<BasaltCamera>,
    /// `[width, height]` per camera.
    resolution: Vec<[u32; 2]>,
    #[serde(skip_deserializing)]
    calib_accel_bias: [f64; 9],
    #[serde(skip_deserializing)]
    calib_gyro_bias: [f64; 12],
    #[serde(skip_deserializing)]
    imu_update_rate: f64,
    #[serde(skip_deserializing)]
    accel_noise_std: [f64; 3],
    #[serde(skip_deserializing)]
    gyro_noise_std: [f64; 3],
    #[serde(skip_deserializing)]
    accel_bias_std: [f64; 3],
    #[serde(skip_deserializing)]
    gyro_bias_std: [f64; 3],
    #[serde(skip_deserializing)]
    cam_time_offset_ns: i64,
    #[serde(skip_deserializing)]
    vignette: Vec<serde_json::Value>,
}

/// A pose as Basalt writes it: translation (metres) and unit quaternion.
#[derive(Serialize, Deserialize)]
struct BasaltPose {
    px: f64,
    py: f64,
    pz: f64,
    qx: f64,
    qy: f64,
    qz: f64,
    qw: f64,
}

/// One camera's model: its type and its named parameters.
#[derive(Serialize, Deserialize)]
struct BasaltCamera {
    camera_type: String,
    intrinsics: NamedParams,
}

/// Named parameters, written in the model's order (`fx, fy, cx, cy, ...`, as Basalt does);
/// read in any order.
struct NamedParams(Vec<(String, f64)>);

impl Serialize for NamedParams {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for NamedParams {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let map = BTreeMap::<String, f64>::deserialize(deserializer)?;
        Ok(Self(map.into_iter().collect()))
    }
}

/// Reads the rig of a Basalt `calibration.json`.
///
/// # Errors
/// [`CameraError`] naming the file and the field: an unreadable file, invalid JSON, a
/// field missing or of the wrong type, an unknown `camera_type`, a missing or refused
/// parameter, a zero or non-finite quaternion, a zero resolution, or lists of different
/// lengths.
pub fn read_basalt_calibration(path: &Path) -> Result<Rig, CameraError> {
    let text = std::fs::read_to_string(path).map_err(|source| CameraError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_basalt_calibration(path, &text)
}

/// Parses the rig from the text of a Basalt `calibration.json`; `path` is used in errors.
///
/// # Errors
/// As [`read_basalt_calibration`].
pub fn parse_basalt_calibration(path: &Path, text: &str) -> Result<Rig, CameraError> {
    let value: serde_json::Value = serde_json::from_str(text).map_err(|e| CameraError::Line {
        path: path.to_path_buf(),
        line: e.line(),
        message: format!("not valid JSON: {e}"),
    })?;
    let file: BasaltFile = omnimvs_core::yaml::from_value(path, value)?;
    let calib = file.value0;
    let n = calib.intrinsics.len();
    if n == 0 {
        return Err(CameraError::field(
            path,
            "value0.intrinsics",
            "expected at least one camera, found an empty list",
        ));
    }
    for (field, len) in [
        ("value0.T_imu_cam", calib.t_imu_cam.len()),
        ("value0.resolution", calib.resolution.len()),
    ] {
        if len != n {
            return Err(CameraError::field(
                path,
                field,
                format!("expected one entry per camera ({n} in value0.intrinsics), found {len}"),
            ));
        }
    }
    let cameras = (calib.intrinsics.iter().zip(&calib.t_imu_cam))
        .zip(&calib.resolution)
        .enumerate()
        .map(|(i, ((camera, pose), &[width, height]))| {
            if width == 0 || height == 0 {
                return Err(CameraError::field(
                    path,
                    format!("value0.resolution[{i}]"),
                    format!("expected a positive [width, height], found [{width}, {height}]"),
                ));
            }
            let field = format!("value0.intrinsics[{i}]");
            let lens = lens_of(path, &field, camera)?;
            let central = CentralCamera::new(lens, width, height, None)
                .map_err(|e| param_in_field(path, &field, e))?;
            let pose = pose_of(path, &format!("value0.T_imu_cam[{i}]"), pose)?;
            Ok(Camera::new(
                i as u32,
                format!("cam{i}"),
                CameraModel::Central(central),
                pose,
                None,
            ))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Rig::new(cameras))
}

/// The lens of one entry of `intrinsics`; `field` is `value0.intrinsics[i]`.
fn lens_of(path: &Path, field: &str, camera: &BasaltCamera) -> Result<Lens, CameraError> {
    let get = |name: &str| {
        let found = camera.intrinsics.0.iter().find(|(key, _)| key == name);
        found.map(|&(_, value)| value).ok_or_else(|| {
            CameraError::field(
                path,
                format!("{field}.intrinsics.{name}"),
                format!("missing: camera_type {:?} needs it", camera.camera_type),
            )
        })
    };
    // The type is checked before its parameters are looked up.
    let focal = || Ok::<_, CameraError>((get("fx")?, get("fy")?, get("cx")?, get("cy")?));
    let lens = match camera.camera_type.as_str() {
        "ds" => {
            let (fx, fy, cx, cy) = focal()?;
            DoubleSphere::new(fx, fy, cx, cy, get("xi")?, get("alpha")?).map(Lens::DoubleSphere)
        }
        "eucm" => {
            let (fx, fy, cx, cy) = focal()?;
            ExtendedUnified::new(fx, fy, cx, cy, get("alpha")?, get("beta")?)
                .map(Lens::ExtendedUnified)
        }
        "kb4" => {
            let (fx, fy, cx, cy) = focal()?;
            let k = [get("k1")?, get("k2")?, get("k3")?, get("k4")?];
            KannalaBrandt4::new(fx, fy, cx, cy, k[0], k[1], k[2], k[3]).map(Lens::KannalaBrandt4)
        }
        "pinhole" => {
            let (fx, fy, cx, cy) = focal()?;
            PinholeRadtan::new(fx, fy, cx, cy, 0.0, 0.0, 0.0, 0.0).map(Lens::PinholeRadtan)
        }
        "ucm" => {
            let (fx, fy, cx, cy) = focal()?;
            let alpha = get("alpha")?;
            if !(0.0..1.0).contains(&alpha) {
                return Err(CameraError::field(
                    path,
                    format!("{field}.intrinsics.alpha"),
                    format!("expected Basalt's ucm alpha in [0, 1), found {alpha}"),
                ));
            }
            // Basalt's `alpha d + (1 - alpha) z` is `(1 - alpha)(z + xi d)`.
            let s = 1.0 - alpha;
            Unified::new(fx / s, fy / s, cx, cy, alpha / s).map(Lens::Unified)
        }
        other => {
            return Err(CameraError::field(
                path,
                format!("{field}.camera_type"),
                format!("unsupported camera type {other:?}, expected {SUPPORTED}"),
            ));
        }
    };
    lens.map_err(|e| param_in_field(path, field, e))
}

/// The pose of one entry of `T_imu_cam`; `field` is `value0.T_imu_cam[i]`. A quaternion
/// that is not of unit norm is normalised.
fn pose_of(path: &Path, field: &str, p: &BasaltPose) -> Result<Pose, CameraError> {
    let q = Quaternion::new(p.qw, p.qx, p.qy, p.qz);
    let norm = q.norm();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(CameraError::field(
            path,
            field,
            format!("expected a unit quaternion (qx, qy, qz, qw), found norm {norm}"),
        ));
    }
    let t = [p.px, p.py, p.pz];
    if t.iter().any(|v| !v.is_finite()) {
        return Err(CameraError::field(
            path,
            field,
            "expected a finite translation (px, py, pz)",
        ));
    }
    let rotation = UnitQuaternion::from_quaternion(q);
    Ok(Pose::from_isometry(&nalgebra::Isometry3::from_parts(
        Translation3::from(Vector3::from(t)),
        rotation,
    )))
}

/// The text of a Basalt `calibration.json` for `rig`: `T_imu_cam` from each camera's
/// `rig_from_cam` (the rig frame becomes Basalt's IMU frame), the named parameters, the
/// resolutions, and the IMU fields Basalt needs to load the file with neutral values (zero
/// biases and noise, 200 Hz, no time offset, no vignette). Numbers at full precision: reading
/// the text back gives the same intrinsics bit for bit, except a `ucm` camera's, which go
/// through Basalt's parametrisation and come back within a few units in the last place.
///
/// # Errors
/// [`CameraError::Field`] naming `calibration.json` and `cameras[i].model` for a camera
/// Basalt cannot state: OCamCalib, pinhole or unified with distortion, or a field of view
/// other than the lens model's widest; [`CameraError::Field`] naming `cameras` for an empty
/// rig.
pub fn basalt_calibration_json(rig: &Rig) -> Result<String, CameraError> {
    const TOOL: &str = "Basalt's calibration.json";
    if rig.is_empty() {
        return Err(CameraError::field(
            FILE,
            "cameras",
            "expected at least one camera",
        ));
    }
    let mut calib = BasaltCalibration {
        t_imu_cam: Vec::new(),
        intrinsics: Vec::new(),
        resolution: Vec::new(),
        calib_accel_bias: [0.0; 9],
        calib_gyro_bias: [0.0; 12],
        imu_update_rate: 200.0,
        accel_noise_std: [0.0; 3],
        gyro_noise_std: [0.0; 3],
        accel_bias_std: [0.0; 3],
        gyro_bias_std: [0.0; 3],
        cam_time_offset_ns: 0,
        vignette: Vec::new(),
    };
    for (i, cam) in rig.cameras.iter().enumerate() {
        let central = central_with_model_fov(cam, i, FILE, TOOL)?;
        let distorted = |model: &str| {
            unsupported(
                FILE,
                i,
                format!(
                    "{TOOL} has no {model} camera with radial-tangential distortion; \
                     write Kalibr's camchain.yaml or config.yaml instead"
                ),
            )
        };
        let f = central.lens.focal();
        let focal = |fx, fy| [("fx", fx), ("fy", fy), ("cx", f.cx()), ("cy", f.cy())];
        let (camera_type, params): (&str, Vec<(&'static str, f64)>) = match &central.lens {
            Lens::DoubleSphere(m) => (
                "ds",
                [
                    &focal(f.fx(), f.fy())[..],
                    &[("xi", m.xi()), ("alpha", m.alpha())],
                ]
                .concat(),
            ),
            Lens::ExtendedUnified(m) => (
                "eucm",
                [
                    &focal(f.fx(), f.fy())[..],
                    &[("alpha", m.alpha()), ("beta", m.beta())],
                ]
                .concat(),
            ),
            Lens::KannalaBrandt4(m) => {
                let [k1, k2, k3, k4] = m.k();
                let k = [("k1", k1), ("k2", k2), ("k3", k3), ("k4", k4)];
                ("kb4", [&focal(f.fx(), f.fy())[..], &k].concat())
            }
            Lens::PinholeRadtan(m) if m.radtan() == [0.0; 4] => {
                ("pinhole", focal(f.fx(), f.fy()).to_vec())
            }
            Lens::PinholeRadtan(_) => return Err(distorted("pinhole")),
            Lens::Unified(m) if m.radtan() == [0.0; 4] => {
                let s = 1.0 + m.xi();
                let alpha = [("alpha", m.xi() / s)];
                ("ucm", [&focal(f.fx() / s, f.fy() / s)[..], &alpha].concat())
            }
            Lens::Unified(_) => return Err(distorted("unified")),
        };
        let rig_from_cam = cam.pose.rig_from_cam();
        let (t, q) = (rig_from_cam.translation.vector, rig_from_cam.rotation);
        calib.t_imu_cam.push(BasaltPose {
            px: t.x,
            py: t.y,
            pz: t.z,
            qx: q.i,
            qy: q.j,
            qz: q.k,
            qw: q.w,
        });
        calib.intrinsics.push(BasaltCamera {
            camera_type: camera_type.to_string(),
            intrinsics: NamedParams(
                params
                    .into_iter()
                    .map(|(name, value)| (name.to_string(), value))
                    .collect(),
            ),
        });
        calib.resolution.push([central.width, central.height]);
    }
    serde_json::to_string_pretty(&BasaltFile { value0: calib })
        .map_err(|e| CameraError::field(FILE, "value0", format!("cannot write as JSON: {e}")))
}
