//! Opening a dataset the way every command does: a `config.yaml` dataset, a folder with a
//! calibration tool's file, or a folder in the released layout whose `poses.txt` translations
//! are in the unit of the global `--pose-unit` (centimetres unless stated); in the frame of the
//! global `--rig-frame`, with the global `--min-depth`. `main` passes them to the commands
//! that open datasets.

use std::path::Path;

use anyhow::{Context, Result};
use omnimvs_camera::{FrameChoice, LengthUnit};
use omnimvs_data::{Dataset, OpenOptions};

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

/// `--rig-frame` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RigFrameArg {
    /// The calibration file's own frame.
    Calibration,
    /// Centred at the cameras' mean, vertical axis normal to the plane they span.
    Fitted,
}

/// Opens datasets the way every command does, with the global `--pose-unit`, `--rig-frame`
/// and `--min-depth` as stated on the command line.
#[derive(Debug, Clone, Copy, Default)]
pub struct DatasetOpener {
    options: OpenOptions,
    stated: Option<&'static str>,
}

impl DatasetOpener {
    /// An opener with the global options' values (`None`: not stated).
    pub fn new(
        pose_unit: Option<PoseUnit>,
        rig_frame: Option<RigFrameArg>,
        min_depth_m: Option<f64>,
    ) -> Self {
        let stated = [
            pose_unit.map(|_| "--pose-unit"),
            rig_frame.map(|_| "--rig-frame"),
            min_depth_m.map(|_| "--min-depth"),
        ]
        .into_iter()
        .flatten()
        .next();
        Self {
            options: OpenOptions {
                pose_unit: pose_unit.map(LengthUnit::from),
                frame: match rig_frame {
                    Some(RigFrameArg::Fitted) => FrameChoice::Fitted,
                    _ => FrameChoice::Calibration,
                },
                min_depth_m,
                rig_only: false,
            },
            stated,
        }
    }

    /// The options as stated.
    pub fn options(&self) -> &OpenOptions {
        &self.options
    }

    /// The stated pose unit, if any.
    pub fn pose_unit(&self) -> Option<LengthUnit> {
        self.options.pose_unit
    }

    /// Opens the dataset at `path` with the stated options.
    ///
    /// # Errors
    /// The library's error, with the options named when one was stated.
    pub fn open(&self, path: &Path) -> Result<Dataset> {
        self.open_with(path, &self.options)
    }

    /// [`Self::open`] for the rig alone: a calibration file or a folder without images opens
    /// too (`OpenOptions::rig_only`).
    ///
    /// # Errors
    /// As [`Self::open`].
    pub fn open_rig_only(&self, path: &Path) -> Result<Dataset> {
        let options = OpenOptions {
            rig_only: true,
            ..self.options
        };
        self.open_with(path, &options)
    }

    /// Opens `path` with `options`, naming the stated options in an error.
    fn open_with(&self, path: &Path, options: &OpenOptions) -> Result<Dataset> {
        let ds = Dataset::open_with(path, options);
        match self.stated {
            Some(_) => ds.with_context(|| self.describe()),
            None => Ok(ds?),
        }
    }

    /// The stated options, as typed.
    fn describe(&self) -> String {
        let o = &self.options;
        let mut parts = Vec::new();
        if let Some(u) = o.pose_unit {
            parts.push(format!("--pose-unit {u}"));
        }
        if o.frame == FrameChoice::Fitted {
            parts.push("--rig-frame fitted".into());
        }
        if let Some(d) = o.min_depth_m {
            parts.push(format!("--min-depth {d}"));
        }
        parts.join(" ")
    }
}
