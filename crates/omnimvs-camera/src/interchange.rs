//! What the readers and writers of other tools' calibration files (Basalt's
//! `calibration.json`, Kalibr's `camchain.yaml`) share: errors that name the file and the
//! field, and the check that a camera can be stated in a file that has no field of view.

use std::path::Path;

use crate::{Camera, CameraError, CameraModel, CentralCamera, KannalaBrandt4, Lens};

/// A model parameter the lens constructor refused ([`CameraError::Param`]), re-stated as a
/// [`CameraError::Field`] naming the file and `field`; other errors pass through.
pub(crate) fn param_in_field(path: &Path, field: &str, error: CameraError) -> CameraError {
    match error {
        CameraError::Param {
            model,
            param,
            message,
        } => CameraError::field(
            path,
            field,
            format!("{model} parameter `{param}`: {message}"),
        ),
        other => other,
    }
}

/// The error of a writer for camera `index` whose model `file` cannot hold.
pub(crate) fn unsupported(file: &str, index: usize, message: impl Into<String>) -> CameraError {
    CameraError::field(file, format!("cameras[{index}].model"), message)
}

/// The closed-form camera of `cam` (camera `index` of a rig) for a file that states no field
/// of view (`tool` names it in errors, e.g. "Basalt's calibration.json"), whose reader gives
/// every camera its lens model's widest field of view.
///
/// # Errors
/// [`CameraError::Field`] naming `file` and `cameras[index].model` for an OCamCalib camera or
/// a camera whose field of view differs from its lens model's widest.
pub(crate) fn central_with_model_fov<'a>(
    cam: &'a Camera,
    index: usize,
    file: &str,
    tool: &str,
) -> Result<&'a CentralCamera, CameraError> {
    let CameraModel::Central(c) = &cam.model else {
        return Err(unsupported(
            file,
            index,
            format!(
                "{tool} has no {} camera; only closed-form lens models can be written",
                cam.model.name()
            ),
        ));
    };
    let model_fov = default_fov_deg(&c.lens)?;
    if c.max_fov_deg != model_fov {
        return Err(unsupported(
            file,
            index,
            format!(
                "{tool} has no field of view for a {} camera; this one sees {} degrees, \
                 the model's parameters give {model_fov} (write config.yaml instead)",
                c.lens.name(),
                c.max_fov_deg
            ),
        ));
    }
    Ok(c)
}

/// The field of view a reader gives `lens` from its parameters alone, degrees: the model's
/// widest, and for Kannala-Brandt the default bound of [`KannalaBrandt4::new`] (a lens set to
/// another with [`KannalaBrandt4::with_max_fov_deg`] differs from it).
fn default_fov_deg(lens: &Lens) -> Result<f64, CameraError> {
    Ok(match lens {
        Lens::KannalaBrandt4(m) => {
            let f = m.focal();
            let [k1, k2, k3, k4] = m.k();
            KannalaBrandt4::new(f.fx(), f.fy(), f.cx(), f.cy(), k1, k2, k3, k4)?.max_fov_deg()
        }
        other => other.max_fov_deg(),
    })
}
