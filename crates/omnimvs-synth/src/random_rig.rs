//! Random rigs, for training data that covers the rigs users have rather than one: two to
//! eight cameras on a ring, baselines from 5 cm to 60 cm, every closed-form lens model with
//! fields of view of 180 to 250 degrees, square images of 480 to 1216 pixels, cameras tilted
//! up to 15 degrees, and optionally a small calibration error: the dataset's `config.yaml`
//! then states a rig slightly off the one its images were rendered with, as a real
//! calibration is.
//!
//! A rig is drawn from a seed alone (`--rig random:SEED`), so that the same seed gives the
//! same rig on every machine.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use omnimvs_camera::{
    Camera, CameraModel, CentralCamera, DoubleSphere, ExtendedUnified, KannalaBrandt4, Lens, Pose,
    Rig, Unified,
};

use crate::SynthError;
use crate::rng::Rng;

/// The prefix of a random rig's name: `random:SEED`.
pub const RANDOM_PREFIX: &str = "random:";

/// What a random rig may be.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomRigSpec {
    /// Fewest and most cameras.
    pub cameras: (usize, usize),
    /// Shortest and longest distance between neighbouring cameras, metres.
    pub baseline_m: (f64, f64),
    /// Narrowest and widest field of view, degrees.
    pub fov_deg: (f64, f64),
    /// Smallest and largest image side, pixels (square images).
    pub image_px: (u32, u32),
    /// Largest tilt of a camera out of the ring's plane (pitch and roll), degrees.
    pub max_tilt_deg: f64,
    /// Chance that the rig's `config.yaml` carries a calibration error.
    pub calibration_error_chance: f64,
    /// Largest rotation error of a stated camera pose, degrees.
    pub max_rotation_error_deg: f64,
    /// Largest translation error of a stated camera pose, metres.
    pub max_translation_error_m: f64,
    /// Largest relative error of a stated focal length.
    pub max_focal_error: f64,
}

impl Default for RandomRigSpec {
    /// The ranges of the rigs users bring: 2-8 cameras, 0.05-0.6 m, 180-250 degrees,
    /// 480-1216 px, tilts up to 15 degrees, and a calibration error (up to 0.2 degrees, 2 mm
    /// and 0.3 % of the focal length) in half the rigs.
    fn default() -> Self {
        Self {
            cameras: (2, 8),
            baseline_m: (0.05, 0.6),
            fov_deg: (180.0, 250.0),
            image_px: (480, 1216),
            max_tilt_deg: 15.0,
            calibration_error_chance: 0.5,
            max_rotation_error_deg: 0.2,
            max_translation_error_m: 0.002,
            max_focal_error: 0.003,
        }
    }
}

/// A drawn rig: the one its images are rendered with, its minimum depth, and the one its
/// `config.yaml` states when that differs (a calibration error). `crate::rig::RigSource`
/// takes it as it is (`From`).
#[derive(Debug, Clone, PartialEq)]
pub struct RandomRig {
    /// The rig the images are rendered with.
    pub rig: Rig,
    /// The sweep's minimum depth, metres.
    pub min_depth_m: f64,
    /// The rig the dataset states, with a calibration error; `None`: `rig` itself.
    pub stated: Option<Rig>,
}

/// The lens models a random rig draws from.
const MODELS: [&str; 4] = ["ds", "eucm", "ucm", "kb4"];

/// Whether `--rig` names a random rig, and its seed.
///
/// # Errors
/// [`SynthError::Invalid`] for `random:` followed by something other than a whole number.
pub fn parse_random_rig(arg: &str) -> Result<Option<u64>, SynthError> {
    let Some(seed) = arg.strip_prefix(RANDOM_PREFIX) else {
        return Ok(None);
    };
    seed.parse().map(Some).map_err(|_| {
        SynthError::invalid(
            "rig",
            format!("{arg}: expected random:SEED with SEED a whole number"),
        )
    })
}

/// The rig of `seed` within `spec`.
///
/// The cameras sit on a horizontal ring (the rig frame's y axis is vertical, as the
/// published rig's) of the radius that gives the drawn neighbour distance, facing outwards
/// at evenly spaced headings with up to a fifth of the spacing of jitter, each tilted and
/// raised or lowered a little. Every camera has the same lens model and image size (one
/// product on the whole rig), with parameters of its own. The minimum depth grows with the
/// ring: 2.75 radii (the published rig's 1.65 m at 0.6 m), between 0.3 m and 1.65 m, to the
/// centimetre.
///
/// # Errors
/// [`SynthError::Invalid`] for an empty range in `spec`; [`SynthError`] from a camera model
/// (none in practice: the draws stay inside every model's domain).
pub fn random_rig(seed: u64, spec: &RandomRigSpec) -> Result<RandomRig, SynthError> {
    check_spec(spec)?;
    let mut rng = Rng::for_frame(seed, "random-rig", 0);
    let count = spec.cameras.0 + rng.below(spec.cameras.1 - spec.cameras.0 + 1);
    let baseline_m = rng.log_range(spec.baseline_m.0, spec.baseline_m.1);
    // Neighbours at angle 2 pi / n on a circle of radius r are 2 r sin(pi / n) apart; two
    // cameras face away from each other across the diameter.
    let radius_m = baseline_m / (2.0 * (std::f64::consts::PI / count as f64).sin());
    let model = MODELS[rng.below(MODELS.len())];
    let side = rng.range(f64::from(spec.image_px.0), f64::from(spec.image_px.1));
    let side = ((side / 16.0).round() * 16.0) as u32;
    let fov_deg = rng.range(spec.fov_deg.0, spec.fov_deg.1);
    let spacing = 2.0 * std::f64::consts::PI / count as f64;
    let max_tilt = spec.max_tilt_deg.to_radians();
    let heading0 = rng.range(0.0, spacing);
    let cameras = (0..count)
        .map(|i| {
            let mut c = rng.fork();
            let heading = heading0 + spacing * i as f64 + c.range(-0.2, 0.2) * spacing;
            let pitch = c.range(-max_tilt, max_tilt);
            let roll = c.range(-max_tilt, max_tilt);
            let rotation = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), heading)
                * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), pitch)
                * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), roll);
            let height_m = c.range(-0.05, 0.05) * radius_m;
            let centre = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), heading)
                * Vector3::new(0.0, height_m, radius_m);
            let rig_from_cam = Isometry3::from_parts(Translation3::from(centre), rotation);
            let lens = random_lens(&mut c, model, fov_deg, side)?;
            let camera = CentralCamera::new(lens, side, side, Some(fov_deg))?;
            Ok(Camera::new(
                (i + 1) as u32,
                format!("cam{}", i + 1),
                CameraModel::Central(camera),
                Pose::from_isometry(&rig_from_cam),
                None,
            ))
        })
        .collect::<Result<Vec<_>, SynthError>>()?;
    let rig = Rig::new(cameras);
    let stated = if rng.chance(spec.calibration_error_chance) {
        Some(with_calibration_error(&rig, &mut rng, spec)?)
    } else {
        None
    };
    Ok(RandomRig {
        rig,
        min_depth_m: ((2.75 * radius_m).clamp(0.3, 1.65) * 100.0).round() / 100.0,
        stated,
    })
}

fn check_spec(spec: &RandomRigSpec) -> Result<(), SynthError> {
    let ordered = |lo: f64, hi: f64| lo > 0.0 && lo <= hi && hi.is_finite();
    let bad = |field: &str, expected: &str| Err(SynthError::invalid(field, expected.to_string()));
    if !(spec.cameras.0 >= 2 && spec.cameras.0 <= spec.cameras.1) {
        return bad("cameras", "expected at least two cameras, fewest <= most");
    }
    if !ordered(spec.baseline_m.0, spec.baseline_m.1) {
        return bad("baseline", "expected 0 < shortest <= longest");
    }
    if !(ordered(spec.fov_deg.0, spec.fov_deg.1) && spec.fov_deg.1 <= 250.0) {
        return bad("fov", "expected 0 < narrowest <= widest <= 250 degrees");
    }
    if !(spec.image_px.0 >= 64 && spec.image_px.0 <= spec.image_px.1) {
        return bad("image size", "expected 64 <= smallest <= largest");
    }
    Ok(())
}

/// A lens of `model` seeing `fov_deg` on a `side x side` image: its shape drawn from the
/// ranges calibrations of real fisheye lenses give (drawn again until the model's domain
/// holds the field of view), its focal length set so that the edge of the field of view lies
/// at 46-49 % of the side from the centre, its principal point within 1 % of the side of the
/// image centre.
fn random_lens(rng: &mut Rng, model: &str, fov_deg: f64, side: u32) -> Result<Lens, SynthError> {
    let half_fov = (fov_deg / 2.0).to_radians();
    let side_px = f64::from(side);
    let centre = side_px / 2.0 - 0.5;
    let cx = centre + rng.range(-0.01, 0.01) * side_px;
    let cy = centre + rng.range(-0.01, 0.01) * side_px;
    let aspect = rng.range(0.995, 1.005);
    let edge_px = rng.range(0.46, 0.49) * side_px;
    for _ in 0..100 {
        let shape = [rng.f64(), rng.f64()];
        let lens = |f: f64, cx: f64, cy: f64| -> Result<Lens, SynthError> {
            let mix = |k: usize, lo: f64, hi: f64| lo + shape[k] * (hi - lo);
            let fy = f * aspect;
            Ok(match model {
                "ds" => Lens::DoubleSphere(DoubleSphere::new(
                    f,
                    fy,
                    cx,
                    cy,
                    mix(0, -0.3, 0.1),
                    mix(1, 0.5, 0.65),
                )?),
                "eucm" => Lens::ExtendedUnified(ExtendedUnified::new(
                    f,
                    fy,
                    cx,
                    cy,
                    mix(0, 0.55, 0.7),
                    mix(1, 0.9, 1.2),
                )?),
                "ucm" => Lens::Unified(Unified::new(f, fy, cx, cy, mix(0, 0.9, 1.6))?),
                _ => Lens::KannalaBrandt4(KannalaBrandt4::new(
                    f,
                    fy,
                    cx,
                    cy,
                    mix(0, -0.03, 0.03),
                    mix(1, -0.005, 0.005),
                    0.0,
                    0.0,
                )?),
            })
        };
        let unit = lens(1.0, 0.0, 0.0)?;
        if unit.max_fov_deg() < fov_deg {
            continue;
        }
        // The image radius of the field of view's edge at unit focal length.
        let edge = Vector3::new(half_fov.sin(), 0.0, half_fov.cos());
        let Some(radius) = unit.project(&edge).map(|px| px.col) else {
            continue;
        };
        if radius > 0.0 && radius.is_finite() {
            return lens(edge_px / radius, cx, cy);
        }
    }
    Err(SynthError::invalid(
        "rig",
        format!("no {model} lens of this generator sees {fov_deg:.1} degrees"),
    ))
}

/// `rig` as a calibration of it would state it: each camera's pose off by a rotation of up
/// to `max_rotation_error_deg` about a random axis and a translation of up to
/// `max_translation_error_m`, its focal lengths off by up to `max_focal_error` (relative).
fn with_calibration_error(
    rig: &Rig,
    rng: &mut Rng,
    spec: &RandomRigSpec,
) -> Result<Rig, SynthError> {
    let cameras = rig
        .cameras
        .iter()
        .map(|camera| {
            let mut c = rng.fork();
            let axis = nalgebra::Unit::new_normalize(c.marsaglia());
            let angle = c.range(0.0, spec.max_rotation_error_deg.to_radians());
            let shift = c.marsaglia() * c.range(0.0, spec.max_translation_error_m);
            let error = Isometry3::from_parts(
                Translation3::from(shift),
                UnitQuaternion::from_axis_angle(&axis, angle),
            );
            let model = match &camera.model {
                CameraModel::Central(central) => {
                    let scale = 1.0 + c.range(-spec.max_focal_error, spec.max_focal_error);
                    CameraModel::Central(central.with_focal_scaled(scale)?)
                }
                other => other.clone(),
            };
            Ok(Camera::new(
                camera.id,
                camera.img_dir.clone(),
                model,
                Pose::from_isometry(&(camera.rig_from_cam * error)),
                camera.invalid_mask.clone(),
            ))
        })
        .collect::<Result<Vec<_>, SynthError>>()?;
    Ok(Rig::new(cameras))
}
