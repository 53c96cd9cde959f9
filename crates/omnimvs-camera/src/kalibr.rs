//! Kalibr's `camchain.yaml`: read into a [`Rig`] and written from one.
//!
//! Kalibr has no rig frame: `T_cn_cnm1` maps the points of camera `n - 1` into camera `n`
//! (`X_cn = T_cn_cnm1 X_cnm1`), so the rig frame is camera 0's: `rig_from_cam0` is the
//! identity and `rig_from_camN = (T_cN_cN-1 ... T_c1_c0)^-1`. The writer therefore expresses
//! a rig in camera 0's frame; reading its text back gives the same cameras and the same
//! relative poses, with `rig_from_cam0` the identity. Camera `n` gets `id = n`,
//! `img_dir = cam{n}`, no invalid mask, and its lens model's widest field of view (the file
//! states none). `T_cam_imu`, `cam_overlaps`, `rostopic` and `timeshift_cam_imu` are ignored.
//!
//! | `camera_model` | `intrinsics` | `distortion_model` | model |
//! |---|---|---|---|
//! | `pinhole` | `fx fy cx cy` | `radtan` (`k1 k2 p1 p2`) or `none` | [`PinholeRadtan`] |
//! | `pinhole` | `fx fy cx cy` | `equidistant` (`k1 k2 k3 k4`) | [`KannalaBrandt4`] |
//! | `omni` | `xi fx fy cx cy` | `radtan` or `none` | [`Unified`] |
//! | `ds` | `xi alpha fx fy cx cy` | `none` | [`DoubleSphere`] |
//! | `eucm` | `alpha beta fx fy cx cy` | `none` | [`ExtendedUnified`] |

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use serde_saphyr::FlowSeq;

use crate::interchange::{central_with_model_fov, param_in_field};
use crate::{
    Camera, CameraError, CameraModel, CentralCamera, DoubleSphere, ExtendedUnified, KannalaBrandt4,
    Lens, PinholeRadtan, Pose, Rig, Unified,
};

/// The file name errors of the writer name.
const FILE: &str = "camchain.yaml";

/// What the reader supports, as listed in its errors.
const SUPPORTED: &str = "pinhole + radtan | equidistant | none, omni + radtan | none, \
                         ds + none, eucm + none";

/// Largest deviation of `R^T R` from the identity accepted in `T_cn_cnm1`.
const ORTHONORMAL_TOL: f64 = 1e-6;

/// One `camN` entry.
#[derive(Debug, Serialize, Deserialize)]
struct KalibrCamera {
    /// Camera `n - 1` to camera `n`, four rows of four numbers (absent for `cam0`).
    #[serde(rename = "T_cn_cnm1", skip_serializing_if = "Option::is_none")]
    t_cn_cnm1: Option<Vec<FlowSeq<Vec<f64>>>>,
    camera_model: String,
    distortion_coeffs: FlowSeq<Vec<f64>>,
    distortion_model: String,
    intrinsics: FlowSeq<Vec<f64>>,
    /// `[width, height]`.
    resolution: FlowSeq<[u32; 2]>,
}

/// The cameras in order, written as the map `cam0: ..., cam1: ...`.
struct CamChain(Vec<KalibrCamera>);

impl Serialize for CamChain {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (n, cam) in self.0.iter().enumerate() {
            map.serialize_entry(&format!("cam{n}"), cam)?;
        }
        map.end()
    }
}

/// Reads the rig of a Kalibr `camchain.yaml`, in camera 0's frame.
///
/// # Errors
/// [`CameraError`] naming the file and the field: an unreadable file, invalid YAML, keys
/// other than consecutive `cam0`, `cam1`, ..., a field missing or of the wrong type, an
/// unsupported camera or distortion model, a list of the wrong length, a parameter the model
/// refuses, a zero resolution, or a missing or malformed `T_cn_cnm1`.
pub fn read_kalibr_camchain(path: &Path) -> Result<Rig, CameraError> {
    let text = std::fs::read_to_string(path).map_err(|source| CameraError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_kalibr_camchain(path, &text)
}

/// Parses the rig from the text of a Kalibr `camchain.yaml`; `path` is used in errors.
///
/// # Errors
/// As [`read_kalibr_camchain`].
pub fn parse_kalibr_camchain(path: &Path, text: &str) -> Result<Rig, CameraError> {
    let value = omnimvs_core::yaml::parse_yaml(path, text)?;
    let Some(map) = value.as_object() else {
        return Err(CameraError::field(
            path,
            "(top level)",
            "expected a map of cameras cam0, cam1, ...",
        ));
    };
    let mut numbers = Vec::new();
    for key in map.keys() {
        let n = key
            .strip_prefix("cam")
            .and_then(|n| n.parse::<usize>().ok());
        match n {
            Some(n) if key == &format!("cam{n}") => numbers.push(n),
            _ => {
                return Err(CameraError::field(
                    path,
                    key,
                    "unexpected key, expected cameras cam0, cam1, ...",
                ));
            }
        }
    }
    numbers.sort_unstable();
    if let Some(missing) = (0..).zip(&numbers).find(|&(want, &n)| want != n) {
        return Err(CameraError::field(
            path,
            format!("cam{}", missing.0),
            format!(
                "missing: the cameras must be numbered cam0, cam1, ... without a gap; \
                 the next one is cam{}",
                missing.1
            ),
        ));
    }
    if numbers.is_empty() {
        return Err(CameraError::field(
            path,
            "cam0",
            "missing: expected at least one camera",
        ));
    }
    let entries: BTreeMap<String, KalibrCamera> = omnimvs_core::yaml::from_value(path, value)?;
    let mut cam_from_cam0 = Isometry3::identity();
    let mut cameras = Vec::with_capacity(numbers.len());
    for n in 0..numbers.len() {
        let key = format!("cam{n}");
        let Some(entry) = entries.get(&key) else {
            continue; // every key was checked above
        };
        let central = central_of(path, &key, entry)?;
        if n > 0 {
            let Some(rows) = &entry.t_cn_cnm1 else {
                return Err(CameraError::field(
                    path,
                    format!("{key}.T_cn_cnm1"),
                    "missing: every camera after cam0 needs its pose relative to the previous one",
                ));
            };
            cam_from_cam0 = isometry_of(path, &format!("{key}.T_cn_cnm1"), rows)? * cam_from_cam0;
        }
        cameras.push(Camera::new(
            n as u32,
            key,
            CameraModel::Central(central),
            Pose::from_isometry(&cam_from_cam0.inverse()),
            None,
        ));
    }
    Ok(Rig::new(cameras))
}

/// The camera of one `camN` entry; `key` is `camN`.
fn central_of(path: &Path, key: &str, e: &KalibrCamera) -> Result<CentralCamera, CameraError> {
    let field =
        |name: &str, message: String| CameraError::field(path, format!("{key}.{name}"), message);
    let (model, distortion) = (e.camera_model.as_str(), e.distortion_model.as_str());
    let i = e.intrinsics.0.as_slice();
    let d = e.distortion_coeffs.0.as_slice();
    let count = |name: &str, values: &[f64], want: &str| {
        field(
            name,
            format!(
                "expected {want} for {model} + {distortion}, found {} numbers",
                values.len()
            ),
        )
    };
    let radtan = || match distortion {
        "none" if d.is_empty() => Ok([0.0; 4]),
        "none" => Err(count("distortion_coeffs", d, "[] (no coefficients)")),
        _ => <[f64; 4]>::try_from(d).map_err(|_| count("distortion_coeffs", d, "[k1, k2, p1, p2]")),
    };
    let lens = match (model, distortion) {
        ("pinhole", "radtan" | "none") => {
            let &[fx, fy, cx, cy] = i else {
                return Err(count("intrinsics", i, "[fx, fy, cx, cy]"));
            };
            let [k1, k2, p1, p2] = radtan()?;
            PinholeRadtan::new(fx, fy, cx, cy, k1, k2, p1, p2).map(Lens::PinholeRadtan)
        }
        ("pinhole", "equidistant") => {
            let &[fx, fy, cx, cy] = i else {
                return Err(count("intrinsics", i, "[fx, fy, cx, cy]"));
            };
            let &[k1, k2, k3, k4] = d else {
                return Err(count("distortion_coeffs", d, "[k1, k2, k3, k4]"));
            };
            KannalaBrandt4::new(fx, fy, cx, cy, k1, k2, k3, k4).map(Lens::KannalaBrandt4)
        }
        ("omni", "radtan" | "none") => {
            let &[xi, fx, fy, cx, cy] = i else {
                return Err(count("intrinsics", i, "[xi, fx, fy, cx, cy]"));
            };
            Unified::with_radtan(fx, fy, cx, cy, xi, radtan()?).map(Lens::Unified)
        }
        ("ds", "none") => {
            let &[xi, alpha, fx, fy, cx, cy] = i else {
                return Err(count("intrinsics", i, "[xi, alpha, fx, fy, cx, cy]"));
            };
            radtan()?;
            DoubleSphere::new(fx, fy, cx, cy, xi, alpha).map(Lens::DoubleSphere)
        }
        ("eucm", "none") => {
            let &[alpha, beta, fx, fy, cx, cy] = i else {
                return Err(count("intrinsics", i, "[alpha, beta, fx, fy, cx, cy]"));
            };
            radtan()?;
            ExtendedUnified::new(fx, fy, cx, cy, alpha, beta).map(Lens::ExtendedUnified)
        }
        ("pinhole" | "omni" | "ds" | "eucm", _) => {
            return Err(field(
                "distortion_model",
                format!(
                    "unsupported distortion model {distortion:?} for camera model {model:?}, expected one of {SUPPORTED}"
                ),
            ));
        }
        _ => {
            return Err(field(
                "camera_model",
                format!("unsupported camera model {model:?}, expected one of {SUPPORTED}"),
            ));
        }
    };
    let lens = lens.map_err(|e| param_in_field(path, &format!("{key}.intrinsics"), e))?;
    let [width, height] = e.resolution.0;
    if width == 0 || height == 0 {
        return Err(field(
            "resolution",
            format!("expected a positive [width, height], found [{width}, {height}]"),
        ));
    }
    CentralCamera::new(lens, width, height, None).map_err(|e| param_in_field(path, key, e))
}

/// The isometry of a 4x4 homogeneous matrix given as rows; the rotation part must be
/// orthonormal to 1e-6 with determinant +1 and is re-orthonormalised (nearest rotation, by
/// SVD).
fn isometry_of(
    path: &Path,
    field: &str,
    rows: &[FlowSeq<Vec<f64>>],
) -> Result<Isometry3<f64>, CameraError> {
    let bad = |message: String| CameraError::field(path, field, message);
    let shape: Vec<usize> = rows.iter().map(|r| r.0.len()).collect();
    if shape != [4, 4, 4, 4] {
        return Err(bad(format!(
            "expected a 4x4 matrix (four rows of four numbers), found rows of lengths {shape:?}"
        )));
    }
    let m = Matrix4::from_fn(|r, c| rows[r].0[c]);
    if m.iter().any(|v| !v.is_finite()) {
        return Err(bad("expected finite numbers".into()));
    }
    let last = m.row(3);
    if (last - nalgebra::RowVector4::new(0.0, 0.0, 0.0, 1.0)).amax() > 1e-9 {
        return Err(bad(format!(
            "expected the last row [0, 0, 0, 1], found [{}, {}, {}, {}]",
            last[0], last[1], last[2], last[3]
        )));
    }
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let deviation = (r.transpose() * r - Matrix3::identity()).amax();
    if deviation > ORTHONORMAL_TOL || r.determinant() <= 0.0 {
        return Err(bad(format!(
            "expected a rotation in the upper-left 3x3 block (R^T R = I to {ORTHONORMAL_TOL}, \
             det R = +1), found |R^T R - I| = {deviation:e}, det R = {}",
            r.determinant()
        )));
    }
    let svd = r.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(bad("cannot decompose the rotation block".into()));
    };
    let rotation = Rotation3::from_matrix_unchecked(u * v_t);
    let t = Vector3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
    Ok(Isometry3::from_parts(
        Translation3::from(t),
        UnitQuaternion::from_rotation_matrix(&rotation),
    ))
}

/// The rows of an isometry's 4x4 matrix, each a flow list.
fn rows_of(iso: &Isometry3<f64>) -> Vec<FlowSeq<Vec<f64>>> {
    let m = iso.to_homogeneous();
    (0..4)
        .map(|r| FlowSeq((0..4).map(|c| m[(r, c)]).collect()))
        .collect()
}

/// The text of a Kalibr `camchain.yaml` for `rig`: each camera's model, and for cameras
/// after the first `T_cn_cnm1` from the rig's poses, so that the rig is expressed in camera
/// 0's frame (see the module documentation). Numbers at full precision: reading the text back
/// gives the same intrinsics bit for bit and the same relative poses up to rounding.
///
/// # Errors
/// [`CameraError::Field`] naming `camchain.yaml` and `cameras[i].model` for a camera Kalibr
/// cannot state: OCamCalib, or a field of view other than the lens model's widest;
/// [`CameraError::Field`] naming `cameras` for an empty rig; [`CameraError::Yaml`] if the
/// serialiser fails.
pub fn kalibr_camchain_yaml(rig: &Rig) -> Result<String, CameraError> {
    const TOOL: &str = "Kalibr's camchain.yaml";
    if rig.is_empty() {
        return Err(CameraError::field(
            FILE,
            "cameras",
            "expected at least one camera",
        ));
    }
    let mut chain = Vec::with_capacity(rig.len());
    for (n, cam) in rig.cameras.iter().enumerate() {
        let central = central_with_model_fov(cam, n, FILE, TOOL)?;
        let f = central.lens.focal();
        let (fx, fy, cx, cy) = (f.fx(), f.fy(), f.cx(), f.cy());
        let (model, intrinsics, distortion, coeffs) = match &central.lens {
            Lens::PinholeRadtan(m) => (
                "pinhole",
                vec![fx, fy, cx, cy],
                "radtan",
                m.radtan().to_vec(),
            ),
            Lens::KannalaBrandt4(m) => (
                "pinhole",
                vec![fx, fy, cx, cy],
                "equidistant",
                m.k().to_vec(),
            ),
            Lens::Unified(m) if m.radtan() == [0.0; 4] => {
                ("omni", vec![m.xi(), fx, fy, cx, cy], "none", Vec::new())
            }
            Lens::Unified(m) => (
                "omni",
                vec![m.xi(), fx, fy, cx, cy],
                "radtan",
                m.radtan().to_vec(),
            ),
            Lens::DoubleSphere(m) => (
                "ds",
                vec![m.xi(), m.alpha(), fx, fy, cx, cy],
                "none",
                Vec::new(),
            ),
            Lens::ExtendedUnified(m) => (
                "eucm",
                vec![m.alpha(), m.beta(), fx, fy, cx, cy],
                "none",
                Vec::new(),
            ),
        };
        let t_cn_cnm1 = (n > 0).then(|| {
            let previous = rig.cameras[n - 1].pose.rig_from_cam();
            rows_of(&(cam.pose.rig_from_cam().inverse() * previous))
        });
        chain.push(KalibrCamera {
            t_cn_cnm1,
            camera_model: model.into(),
            distortion_coeffs: FlowSeq(coeffs),
            distortion_model: distortion.into(),
            intrinsics: FlowSeq(intrinsics),
            resolution: FlowSeq([central.width, central.height]),
        });
    }
    Ok(omnimvs_core::yaml::to_yaml(
        "a camchain.yaml",
        &CamChain(chain),
    )?)
}
