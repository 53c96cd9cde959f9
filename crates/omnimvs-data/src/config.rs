use std::path::Path;

use omnimvs_camera::{ConfigCamera, ConfigFile, DatasetSection, Rig, SweepSection};
use serde_saphyr::{DoubleQuoted, FlowSeq};

use crate::DataError;

/// The frame indices `start, start+step, ..., <= end` of a dataset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    pub start: u32,
    pub step: u32,
    pub end: u32,
}

impl FrameRange {
    /// The frames `start..=end`, step 1.
    pub fn inclusive(start: u32, end: u32) -> Self {
        Self {
            start,
            step: 1,
            end,
        }
    }

    /// The indices of the range.
    pub fn indices(&self) -> Vec<u32> {
        (self.start..=self.end)
            .step_by(self.step.max(1) as usize)
            .collect()
    }

    /// Whether `frame` is one of the range's indices.
    pub fn contains(&self, frame: u32) -> bool {
        (self.start..=self.end).contains(&frame)
            && (frame - self.start).is_multiple_of(self.step.max(1))
    }
}

/// Reads a frame range as the published splits write it: `A..B` (inclusive), `A..=B`, `A-B`
/// or a single frame `A` (step 1).
///
/// # Errors
/// [`DataError::FrameRange`] naming the text: not two frame numbers, or a range whose end is
/// before its start.
impl std::str::FromStr for FrameRange {
    type Err = DataError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let bad = |message: String| DataError::FrameRange {
            text: text.to_string(),
            message,
        };
        let t = text.trim();
        let (a, b) = if let Some((a, b)) = t.split_once("..=") {
            (a, b)
        } else if let Some((a, b)) = t.split_once("..") {
            (a, b)
        } else if let Some((a, b)) = t.split_once('-') {
            (a, b)
        } else {
            (t, t)
        };
        let number = |x: &str| {
            x.trim().parse::<u32>().map_err(|_| {
                bad("expected FIRST..LAST (inclusive) such as 1..10, or a single frame".into())
            })
        };
        let (start, end) = (number(a)?, number(b)?);
        if end < start {
            return Err(bad(format!(
                "the range is reversed: the last frame ({end}) is before the first ({start})"
            )));
        }
        Ok(Self::inclusive(start, end))
    }
}

/// `A..B` (inclusive), with `/STEP` when the step is not 1.
impl std::fmt::Display for FrameRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.start, self.end)?;
        if self.step != 1 {
            write!(f, "/{}", self.step)?;
        }
        Ok(())
    }
}

/// The non-camera parts of a reference `config.yaml`.
#[derive(Debug, Clone, PartialEq)]
pub struct DatasetConfig {
    /// `config.omnimvs_sweep_min_depth`, metres.
    pub min_depth_m: f64,
    /// `dataset.img_fmt`: printf pattern of an image, camera index (1-based)
    /// then frame index, e.g. `cam%d/%05d.png`.
    pub img_fmt: String,
    /// `dataset.start/step/end`.
    pub frames: FrameRange,
    /// `dataset.gt_fmt` if present: printf pattern of a ground-truth file by
    /// frame index, relative to the dataset folder.
    pub gt_fmt: Option<String>,
    /// `dataset.train_idx`, `test_idx` and `gt_phi` if present: the training split as the
    /// reference implementation's `Dataset` reads it from `config.yaml`.
    pub split: Option<Split>,
}

/// A dataset's train/test frames as the reference implementation's `Dataset` takes them.
///
/// The reference knows the published sets' splits by dataset name (`sunny`, `omnithings`,
/// `omnihouse`, ...); for any other name it copies every key of `config.yaml`'s `dataset:`
/// section into its options, so a dataset states its own split there: `train_idx`, `test_idx`
/// (frame numbers), `gt_phi` (latitude range of the ground truth, degrees) and `dtype: gt`
/// (without which the reference loads no ground truth; written whenever a split is).
#[derive(Debug, Clone, PartialEq)]
pub struct Split {
    /// `dataset.train_idx`: the frames the reference trains on.
    pub train: Vec<u32>,
    /// `dataset.test_idx`: the frames it holds out.
    pub test: Vec<u32>,
    /// `dataset.gt_phi`, degrees (90 for a 320x640 ground truth covering +-90 degrees).
    pub gt_phi_deg: Option<f64>,
}

impl DatasetConfig {
    /// Parses the `config:` and `dataset:` sections.
    ///
    /// # Errors
    /// [`DataError`] naming the file and the field.
    pub fn parse(path: &Path, text: &str) -> Result<Self, DataError> {
        Self::of_file(path, &ConfigFile::parse(path, text)?)
    }

    /// The `config:` and `dataset:` sections of a parsed file; `path` is used in errors.
    ///
    /// # Errors
    /// [`DataError::Field`] naming the file and the field: a section missing, a
    /// non-positive depth, a pattern without its integer fields, a bad frame range.
    pub fn of_file(path: &Path, file: &ConfigFile) -> Result<Self, DataError> {
        let field = |field: &str, message: String| DataError::Field {
            path: path.to_path_buf(),
            field: field.to_string(),
            message,
        };
        let (Some(config), Some(dataset)) = (&file.config, &file.dataset) else {
            let missing = if file.config.is_none() {
                "config"
            } else {
                "dataset"
            };
            return Err(field(missing, format!("missing section `{missing}:`")));
        };
        let img_fmt = &dataset.img_fmt.0;
        let gt_fmt = dataset.gt_fmt.as_ref().map(|g| &g.0);
        let min_depth_m = config.omnimvs_sweep_min_depth;
        if !(min_depth_m.is_finite() && min_depth_m > 0.0) {
            return Err(field(
                "config.omnimvs_sweep_min_depth",
                format!("expected a positive depth in metres, found {min_depth_m}"),
            ));
        }
        if crate::format_printf(img_fmt, &[1, 1]).is_none() {
            return Err(field(
                "dataset.img_fmt",
                format!(
                    "expected a pattern with two integer fields (camera, frame) such as \"cam%d/%05d.png\", found {:?}",
                    img_fmt
                ),
            ));
        }
        if let Some(g) = gt_fmt
            && crate::format_printf(g, &[1]).is_none()
        {
            return Err(field(
                "dataset.gt_fmt",
                format!("expected a pattern with one integer field (frame), found {g:?}"),
            ));
        }
        let start = dataset.start.unwrap_or(1);
        let step = dataset.step.unwrap_or(1);
        let end = dataset.end.unwrap_or(start);
        if step == 0 {
            return Err(field(
                "dataset.step",
                "expected a positive step, found 0".into(),
            ));
        }
        if end < start {
            return Err(field(
                "dataset.end",
                format!("expected end >= start ({start}), found {end}"),
            ));
        }
        let list = |l: &Option<FlowSeq<Vec<u32>>>| l.as_ref().map(|l| l.0.clone());
        let split = match (list(&dataset.train_idx), list(&dataset.test_idx)) {
            (None, None) => None,
            (train, test) => Some(Split {
                train: train.unwrap_or_default(),
                test: test.unwrap_or_default(),
                gt_phi_deg: dataset.gt_phi,
            }),
        };
        Ok(Self {
            min_depth_m,
            img_fmt: img_fmt.clone(),
            frames: FrameRange { start, step, end },
            gt_fmt: gt_fmt.cloned(),
            split,
        })
    }
}

/// The text of a reference-layout `config.yaml` for `rig` (the inverse of
/// [`crate::Dataset::open`]'s reader; numbers are written at full precision,
/// so reading the file back gives the same rig bit for bit).
///
/// # Errors
/// [`DataError::Camera`] if the serialiser fails (it does not for a valid rig).
pub fn write_config_yaml(rig: &Rig, config: &DatasetConfig) -> Result<String, DataError> {
    let split = config.split.as_ref();
    let file = ConfigFile {
        config: Some(SweepSection {
            omnimvs_sweep_min_depth: config.min_depth_m,
        }),
        dataset: Some(DatasetSection {
            img_fmt: DoubleQuoted(config.img_fmt.clone()),
            gt_fmt: config.gt_fmt.clone().map(DoubleQuoted),
            start: Some(config.frames.start),
            step: Some(config.frames.step),
            end: Some(config.frames.end),
            dtype: split.map(|_| "gt".to_string()),
            gt_phi: split.and_then(|s| s.gt_phi_deg),
            train_idx: split.map(|s| FlowSeq(s.train.clone())),
            test_idx: split.map(|s| FlowSeq(s.test.clone())),
        }),
        cameras: ConfigCamera::of_rig(rig),
    };
    Ok(format!("# written by omnimvs\n{}", file.to_yaml()?))
}
