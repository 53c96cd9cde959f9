//! Rigs for the generator: the published rig preset, reading a rig with its
//! minimum depth from a rig file, and resizing a rig's images.

use std::path::Path;

use omnimvs_camera::{
    Camera, ConfigFile, FrameChoice, Rig, RigFormat, parse_config_rig, read_rig_file,
};

use crate::SynthError;

/// Name of the published rig preset (`--rig sunny`).
pub const PRESET_NAME: &str = "sunny";

/// Minimum depth of the published rig, metres.
pub const PRESET_MIN_DEPTH_M: f64 = 1.65;

/// The camera values of the published rig (the same numbers as the public
/// `sunny/config.yaml`: four 220-degree fisheyes, 768x800, 0.6 m from the rig
/// centre). Calibration, not data. No `invalid_mask`: synthetic images have
/// no robot body in view. Kept beside this file in `sunny_cameras.yaml`.
pub const PRESET_CAMERAS_YAML: &str = include_str!("sunny_cameras.yaml");

/// A rig and its minimum depth.
#[derive(Debug, Clone, PartialEq)]
pub struct RigSource {
    /// The rig the images are rendered with.
    pub rig: Rig,
    /// `config.omnimvs_sweep_min_depth`, metres.
    pub min_depth_m: f64,
    /// The rig the dataset's `config.yaml` states, when it differs from [`Self::rig`] (a
    /// calibration error, [`crate::random_rig::RandomRig`]); `None`: `rig` itself.
    pub stated: Option<Rig>,
}

impl From<crate::random_rig::RandomRig> for RigSource {
    fn from(drawn: crate::random_rig::RandomRig) -> Self {
        Self {
            rig: drawn.rig,
            min_depth_m: drawn.min_depth_m,
            stated: drawn.stated,
        }
    }
}

impl RigSource {
    /// A rig stated as it is rendered.
    pub fn new(rig: Rig, min_depth_m: f64) -> Self {
        Self {
            rig,
            min_depth_m,
            stated: None,
        }
    }

    /// The rig the dataset's `config.yaml` states.
    pub fn stated_rig(&self) -> &Rig {
        self.stated.as_ref().unwrap_or(&self.rig)
    }

    /// The same source with every camera's images `height x width` ([`resize_rig`]), the
    /// stated rig's too.
    ///
    /// # Errors
    /// As [`resize_rig`].
    pub fn resized(&self, height: u32, width: u32) -> Result<Self, SynthError> {
        Ok(Self {
            rig: resize_rig(&self.rig, height, width)?,
            min_depth_m: self.min_depth_m,
            stated: self
                .stated
                .as_ref()
                .map(|s| resize_rig(s, height, width))
                .transpose()?,
        })
    }
}

/// The published rig preset.
///
/// # Errors
/// Never in practice (the embedded text is tested); a [`SynthError`] if the
/// embedded text were invalid.
pub fn preset_rig() -> Result<RigSource, SynthError> {
    let rig = parse_config_rig(Path::new("<preset sunny>"), PRESET_CAMERAS_YAML)?;
    Ok(RigSource::new(rig, PRESET_MIN_DEPTH_M))
}

/// The rig of `--rig`: the preset name, or a rig file in any format omnimvs reads (a
/// `config.yaml`, whose `config.omnimvs_sweep_min_depth` gives the minimum depth; a Basalt
/// `calibration.json`; a Kalibr `camchain.yaml`; a released-layout folder), in its calibration
/// frame.
///
/// # Errors
/// [`SynthError`] naming the file and field: unreadable file, invalid YAML
/// or camera fields, a missing or non-positive minimum depth.
pub fn load_rig(arg: &str) -> Result<RigSource, SynthError> {
    load_rig_with(arg, None, FrameChoice::Calibration)
}

/// [`load_rig`] with the minimum depth `min_depth_m` (for files that state none, else
/// [`DEFAULT_MIN_DEPTH_M`]; it replaces a `config.yaml`'s) in the frame `frame`.
///
/// # Errors
/// As [`load_rig`]; a non-positive `min_depth_m`; a fitted frame for cameras that do not span
/// a plane.
pub fn load_rig_with(
    arg: &str,
    min_depth_m: Option<f64>,
    frame: FrameChoice,
) -> Result<RigSource, SynthError> {
    let mut source = if arg == PRESET_NAME || arg == "preset" {
        preset_rig()?
    } else if let Some(seed) = crate::random_rig::parse_random_rig(arg)? {
        crate::random_rig::random_rig(seed, &crate::random_rig::RandomRigSpec::default())?.into()
    } else {
        rig_from_file(Path::new(arg), min_depth_m)?
    };
    if let Some(d) = min_depth_m {
        if !(d.is_finite() && d > 0.0) {
            return Err(SynthError::invalid(
                "minimum depth",
                format!("expected a positive number of metres, found {d}"),
            ));
        }
        source.min_depth_m = d;
    }
    let (rig, frame_from_rig) = source.rig.in_frame(frame)?;
    source.rig = rig;
    source.stated = source.stated.map(|s| s.re_expressed(&frame_from_rig));
    Ok(source)
}

/// Minimum depth of a generated dataset whose rig file states none, metres.
pub const DEFAULT_MIN_DEPTH_M: f64 = 0.55;

/// The rig of a rig file and its minimum depth. A `config.yaml` must state its minimum depth
/// unless `min_depth_m` does; other formats take `min_depth_m` or [`DEFAULT_MIN_DEPTH_M`], and
/// their cameras are renumbered from 1 (`cam1/`..), as the written `config.yaml` names them.
///
/// # Errors
/// [`SynthError`] naming the file and field.
pub fn rig_from_file(path: &Path, min_depth_m: Option<f64>) -> Result<RigSource, SynthError> {
    if RigFormat::detect(path)? != RigFormat::ConfigYaml {
        let (rig, _, _) = read_rig_file(path)?;
        let cameras = rig
            .cameras
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let number = i as u32 + 1;
                Camera::new(
                    number,
                    format!("cam{number}"),
                    c.model.clone(),
                    c.pose,
                    None,
                )
            })
            .collect();
        return Ok(RigSource::new(
            Rig::new(cameras),
            min_depth_m.unwrap_or(DEFAULT_MIN_DEPTH_M),
        ));
    }
    let file = ConfigFile::read(path)?;
    let rig = file.rig(path)?;
    let stated = file.config.map(|c| c.omnimvs_sweep_min_depth);
    let Some(min_depth) = stated.or(min_depth_m) else {
        return Err(SynthError::invalid(
            format!("{}: field `config.omnimvs_sweep_min_depth`", path.display()),
            "expected the minimum depth in metres",
        ));
    };
    if !(min_depth.is_finite() && min_depth > 0.0) {
        return Err(SynthError::invalid(
            format!("{}: field `config.omnimvs_sweep_min_depth`", path.display()),
            format!("expected a positive number of metres, found {min_depth}"),
        ));
    }
    Ok(RigSource::new(rig, min_depth))
}

/// Largest distance of a camera centre from the rig origin, metres.
pub fn rig_radius_m(rig: &Rig) -> f64 {
    rig.cameras
        .iter()
        .map(|c| c.center_in_rig().coords.norm())
        .fold(0.0, f64::max)
}

/// The rig with every camera's images resized to `height x width` pixels:
/// the same rays, at the new resolution ([`omnimvs_camera::CameraModel::resized`]).
///
/// # Errors
/// [`SynthError::Invalid`] for a zero size.
pub fn resize_rig(rig: &Rig, height: u32, width: u32) -> Result<Rig, SynthError> {
    if height == 0 || width == 0 {
        return Err(SynthError::invalid(
            "image size",
            format!("expected a positive HxW, found {height}x{width}"),
        ));
    }
    let cameras = rig
        .cameras
        .iter()
        .map(|cam| {
            Camera::new(
                cam.id,
                cam.img_dir.clone(),
                cam.model.resized(height, width),
                cam.pose,
                None,
            )
        })
        .collect();
    Ok(Rig::new(cameras))
}

/// Parses `HxW` (e.g. `384x400`).
///
/// # Errors
/// [`SynthError::Invalid`] naming the image size and the text.
pub fn parse_size(s: &str) -> Result<(u32, u32), SynthError> {
    let bad = || {
        SynthError::invalid(
            "image size",
            format!("expected HxW such as 768x800, found {s:?}"),
        )
    };
    let (h, w) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (h, w) = (
        h.trim().parse::<u32>().map_err(|_| bad())?,
        w.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if h == 0 || w == 0 || h > 16384 || w > 16384 {
        return Err(bad());
    }
    Ok((h, w))
}

#[cfg(test)]
#[allow(clippy::disallowed_methods)] // fixtures are written directly
mod tests {
    use omnimvs_camera::Pixel;
    use omnimvs_camera::nalgebra::Vector3;

    use super::*;

    #[test]
    fn preset_equals_the_published_sample_rig() {
        let preset = preset_rig().unwrap();
        assert_eq!(preset.rig.len(), 4);
        assert!((rig_radius_m(&preset.rig) - 0.6).abs() < 1e-12);
        let sample = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/omnimvs-samples/sunny_single/config.yaml");
        if let Ok(from_file) = load_rig(sample.to_str().unwrap()) {
            assert_eq!(from_file.min_depth_m, PRESET_MIN_DEPTH_M);
            for (a, b) in preset.rig.cameras.iter().zip(&from_file.rig.cameras) {
                assert_eq!(a.model, b.model);
                assert_eq!(a.pose, b.pose);
            }
        }
    }

    #[test]
    fn resized_rig_sees_the_same_rays() {
        let rig = preset_rig().unwrap().rig;
        let small = resize_rig(&rig, 192, 240).unwrap();
        for (big, sm) in rig.cameras.iter().zip(&small.cameras) {
            for p in [
                Vector3::new(0.3, -0.2, 1.0),
                Vector3::new(-2.0, 0.5, 0.1),
                Vector3::new(0.0, 0.0, 1.0),
            ] {
                let a = big.model.project(&p).unwrap();
                let b = sm.model.project(&p).unwrap();
                assert!(((a.row + 0.5) * 0.25 - 0.5 - b.row).abs() < 1e-9);
                assert!(((a.col + 0.5) * 0.3 - 0.5 - b.col).abs() < 1e-9);
                let ray = sm.model.unproject(Pixel::new(b.col, b.row)).unwrap();
                let ray_big = big.model.unproject(a).unwrap();
                assert!((ray - ray_big).norm() < 1e-9);
            }
        }
    }

    #[test]
    fn bad_sizes_and_rigs_are_rejected() {
        assert_eq!(parse_size("384x400").unwrap(), (384, 400));
        assert!(parse_size("384").is_err());
        assert!(parse_size("0x10").is_err());
        let err = load_rig("/nonexistent/config.yaml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("/nonexistent/config.yaml"), "{err}");
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("config.yaml");
        std::fs::write(&p, PRESET_CAMERAS_YAML).unwrap();
        let err = load_rig(p.to_str().unwrap()).unwrap_err().to_string();
        assert!(err.contains("omnimvs_sweep_min_depth"), "{err}");
    }
}
