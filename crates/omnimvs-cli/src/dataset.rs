//! Opening a dataset the way every command does: a `config.yaml` dataset, or a folder in the
//! released layout whose `poses.txt` translations are in the unit of the global `--pose-unit`
//! (centimetres unless stated).

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{Context, Result};
use omnimvs_camera::LengthUnit;
use omnimvs_data::Dataset;

/// `--pose-unit` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PoseUnit {
    /// Metres.
    M,
    /// Centimetres (the released OmniThings, OmniHouse and urban sets).
    Cm,
    /// Millimetres (SweepNet's real_indoor_sample).
    Mm,
}

impl From<PoseUnit> for LengthUnit {
    fn from(u: PoseUnit) -> Self {
        match u {
            PoseUnit::M => Self::Metre,
            PoseUnit::Cm => Self::Centimetre,
            PoseUnit::Mm => Self::Millimetre,
        }
    }
}

/// The unit stated on the command line, set once by `main`.
static POSE_UNIT: OnceLock<Option<LengthUnit>> = OnceLock::new();

/// Records `--pose-unit` for [`open_dataset`]; called once, before any command runs.
pub fn set_pose_unit(unit: Option<PoseUnit>) {
    // Only `main` sets it, once; a second call would keep the first value.
    let _ = POSE_UNIT.set(unit.map(LengthUnit::from));
}

/// The stated pose unit, if any.
pub fn pose_unit() -> Option<LengthUnit> {
    POSE_UNIT.get().copied().flatten()
}

/// Opens the dataset at `path` with the stated pose unit.
///
/// # Errors
/// The library's error, with `--pose-unit` named when it was stated.
pub fn open_dataset(path: &Path) -> Result<Dataset> {
    let unit = pose_unit();
    let ds = Dataset::open_with(path, unit);
    match unit {
        Some(u) => ds.with_context(|| format!("--pose-unit {u}")),
        None => Ok(ds?),
    }
}
