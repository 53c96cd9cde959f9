//! Opening a dataset the way every command does: a `config.yaml` dataset, or a folder in the
//! released layout whose `poses.txt` translations are in the unit of the global `--pose-unit`
//! (centimetres unless stated), which `main` passes to the commands that open datasets.

use std::path::Path;

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

/// Opens datasets the way every command does, with the global `--pose-unit` as stated on the
/// command line (`None`: not stated).
#[derive(Debug, Clone, Copy, Default)]
pub struct DatasetOpener {
    pose_unit: Option<LengthUnit>,
}

impl DatasetOpener {
    /// An opener with `--pose-unit`'s value.
    pub fn new(pose_unit: Option<PoseUnit>) -> Self {
        Self {
            pose_unit: pose_unit.map(LengthUnit::from),
        }
    }

    /// The stated pose unit, if any.
    pub fn pose_unit(&self) -> Option<LengthUnit> {
        self.pose_unit
    }

    /// Opens the dataset at `path` with the stated pose unit.
    ///
    /// # Errors
    /// The library's error, with `--pose-unit` named when it was stated.
    pub fn open(&self, path: &Path) -> Result<Dataset> {
        let ds = Dataset::open_with(path, self.pose_unit);
        match self.pose_unit {
            Some(u) => ds.with_context(|| format!("--pose-unit {u}")),
            None => Ok(ds?),
        }
    }
}
