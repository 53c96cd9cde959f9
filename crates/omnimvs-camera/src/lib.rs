//! Camera models and multi-camera rigs for omnidirectional stereo.
//!
//! * [`OcamModel`]: Scaramuzza's OCamCalib fisheye model, exactly as the public
//!   OmniMVS reference code evaluates it (see `FORMATS.md`).
//! * [`Rig`]: any number of cameras, each with its `rig_from_cam` pose.
//! * Readers for the reference `config.yaml` ([`read_config_rig`]) and for the
//!   released datasets' `ocamN.txt` + `poses.txt` ([`read_ocam_txt_rig`]).
//! * Readers and writers of other tools' calibration files: Basalt's
//!   `calibration.json` ([`read_basalt_calibration`], [`basalt_calibration_json`];
//!   poses in Basalt's IMU frame) and Kalibr's `camchain.yaml`
//!   ([`read_kalibr_camchain`], [`kalibr_camchain_yaml`]; poses in the first
//!   camera's frame).
//! * [`read_rig_file`] and [`write_rig_file`]: any of these formats, told apart
//!   by the path ([`RigFormat::detect`]).
//! * [`ValidityMask`]: the pixels of a fisheye image that carry scene content.
//! * [`models`]: the double sphere, extended unified, unified, Kannala-Brandt
//!   and pinhole radial-tangential models, with exact projection and
//!   unprojection.
//!
//! Frames: the camera frame has x right (image columns), y down (image rows),
//! z forward (optical axis). Pixel positions are [`Pixel`] `(col, row)`,
//! 0-based, in pixel units; OCamCalib's `(row, col)` order is converted where
//! files are read.

mod basalt;
mod batch;
mod central;
mod config_yaml;
mod error;
mod frame;
mod interchange;
mod kalibr;
mod mask;
mod model;
pub mod models;
mod ocam;
mod ocam_txt;
mod pixel;
mod pose;
mod radial;
mod rig;
mod rig_file;

// The unit tests' camera, shared with the property tests.
#[cfg(test)]
#[path = "../tests/support/sunny_cam1.rs"]
mod sunny_cam1;

pub use basalt::{basalt_calibration_json, parse_basalt_calibration, read_basalt_calibration};
pub use central::{CentralCamera, Lens};
pub use config_yaml::{
    ConfigCamera, ConfigFile, DatasetSection, SweepSection, config_cameras_yaml, parse_config_rig,
    read_config_rig,
};
pub use error::CameraError;
pub use frame::FrameChoice;
pub use kalibr::{kalibr_camchain_yaml, parse_kalibr_camchain, read_kalibr_camchain};
pub use mask::ValidityMask;
pub use model::{CameraModel, RESOLUTION_ANGLE_DEG};
pub use models::{DoubleSphere, ExtendedUnified, KannalaBrandt4, PinholeRadtan, Unified};
pub use ocam::OcamModel;
pub use ocam_txt::{
    LengthUnit, parse_ocam_txt, read_ocam_txt_rig, read_ocam_txt_rig_in, write_ocam_txt_rig,
};
pub use pixel::Pixel;
pub use pose::{Pose, isometry_from_pose};
pub use radial::RadialProjection;
pub use rig::{Camera, Rig};
pub use rig_file::{RigFormat, read_rig_file, write_rig_file};

/// Re-exported so that callers use the same nalgebra version.
pub use nalgebra;
