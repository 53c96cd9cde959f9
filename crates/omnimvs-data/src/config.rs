use std::path::Path;

use omnimvs_camera::yaml::{from_value, parse_yaml, to_yaml};
use omnimvs_camera::{ConfigCamera, Rig};
use serde::{Deserialize, Serialize};
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

#[derive(Deserialize)]
struct ConfigSection {
    omnimvs_sweep_min_depth: f64,
}

#[derive(Deserialize)]
struct DatasetSection {
    img_fmt: String,
    start: Option<u32>,
    step: Option<u32>,
    end: Option<u32>,
    gt_fmt: Option<String>,
    train_idx: Option<Vec<u32>>,
    test_idx: Option<Vec<u32>>,
    gt_phi: Option<f64>,
}

#[derive(Deserialize)]
struct Sections {
    config: ConfigSection,
    dataset: DatasetSection,
}

impl DatasetConfig {
    /// Parses the `config:` and `dataset:` sections.
    ///
    /// # Errors
    /// [`DataError`] naming the file and the field.
    pub fn parse(path: &Path, text: &str) -> Result<Self, DataError> {
        let value = parse_yaml(path, text)?;
        let s: Sections = from_value(path, value)?;
        let field = |field: &str, message: String| DataError::Field {
            path: path.to_path_buf(),
            field: field.to_string(),
            message,
        };
        let min_depth_m = s.config.omnimvs_sweep_min_depth;
        if !(min_depth_m.is_finite() && min_depth_m > 0.0) {
            return Err(field(
                "config.omnimvs_sweep_min_depth",
                format!("expected a positive depth in metres, found {min_depth_m}"),
            ));
        }
        if crate::format_printf(&s.dataset.img_fmt, &[1, 1]).is_none() {
            return Err(field(
                "dataset.img_fmt",
                format!(
                    "expected a pattern with two integer fields (camera, frame) such as \"cam%d/%05d.png\", found {:?}",
                    s.dataset.img_fmt
                ),
            ));
        }
        if let Some(g) = &s.dataset.gt_fmt
            && crate::format_printf(g, &[1]).is_none()
        {
            return Err(field(
                "dataset.gt_fmt",
                format!("expected a pattern with one integer field (frame), found {g:?}"),
            ));
        }
        let start = s.dataset.start.unwrap_or(1);
        let step = s.dataset.step.unwrap_or(1);
        let end = s.dataset.end.unwrap_or(start);
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
        let split = match (s.dataset.train_idx, s.dataset.test_idx) {
            (None, None) => None,
            (train, test) => Some(Split {
                train: train.unwrap_or_default(),
                test: test.unwrap_or_default(),
                gt_phi_deg: s.dataset.gt_phi,
            }),
        };
        Ok(Self {
            min_depth_m,
            img_fmt: s.dataset.img_fmt,
            frames: FrameRange { start, step, end },
            gt_fmt: s.dataset.gt_fmt,
            split,
        })
    }
}

/// `config.yaml` as [`write_config_yaml`] writes it: the sections in the reference's order.
#[derive(Serialize)]
struct ConfigFile<'a> {
    config: ConfigSectionOut,
    dataset: DatasetSectionOut<'a>,
    cameras: Vec<ConfigCamera>,
}

#[derive(Serialize)]
struct ConfigSectionOut {
    omnimvs_sweep_min_depth: f64,
}

#[derive(Serialize)]
struct DatasetSectionOut<'a> {
    img_fmt: DoubleQuoted<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gt_fmt: Option<DoubleQuoted<&'a str>>,
    start: u32,
    step: u32,
    end: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    dtype: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gt_phi: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    train_idx: Option<FlowSeq<&'a [u32]>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    test_idx: Option<FlowSeq<&'a [u32]>>,
}

/// The text of a reference-layout `config.yaml` for `rig` (the inverse of
/// [`crate::Dataset::open`]'s reader; numbers are written at full precision,
/// so reading the file back gives the same rig bit for bit).
///
/// # Errors
/// [`DataError::Camera`] if the serialiser fails (it does not for a valid rig).
pub fn write_config_yaml(rig: &Rig, config: &DatasetConfig) -> Result<String, DataError> {
    let file = ConfigFile {
        config: ConfigSectionOut {
            omnimvs_sweep_min_depth: config.min_depth_m,
        },
        dataset: DatasetSectionOut {
            img_fmt: DoubleQuoted(&config.img_fmt),
            gt_fmt: config.gt_fmt.as_deref().map(DoubleQuoted),
            start: config.frames.start,
            step: config.frames.step,
            end: config.frames.end,
            dtype: config.split.as_ref().map(|_| "gt"),
            gt_phi: config.split.as_ref().and_then(|s| s.gt_phi_deg),
            train_idx: config.split.as_ref().map(|s| FlowSeq(s.train.as_slice())),
            test_idx: config.split.as_ref().map(|s| FlowSeq(s.test.as_slice())),
        },
        cameras: ConfigCamera::of_rig(rig),
    };
    Ok(format!(
        "# written by omnimvs\n{}",
        to_yaml("a dataset's config.yaml", &file)?
    ))
}
