//! Opening a dataset folder, whichever way it states its rig: a reference `config.yaml`, the
//! released datasets' `ocamN.txt` + `poses.txt`, or a calibration tool's file (Basalt's
//! `calibration.json`, Kalibr's `camchain.yaml`) beside one image folder per camera.

use std::path::{Path, PathBuf};

use omnimvs_camera::{ConfigFile, FrameChoice, LengthUnit, Pose, Rig, RigFormat};
use serde::Serialize;

use crate::layout::{ImageLayout, mask_beside};
use crate::{DataError, Dataset, DatasetConfig, FrameRange, format_printf};

/// Minimum depth of the released datasets (OmniThings, OmniHouse, the urban sets), metres: their
/// 16-bit ground truth encodes inverse depth relative to `1 / 0.55`. Also the minimum depth of a
/// calibration-file folder, which does not state one, unless [`OpenOptions::min_depth_m`] does.
pub const RELEASED_MIN_DEPTH_M: f64 = 0.55;

/// Field of view of the released rigs' cameras, degrees (their text files do not carry it).
pub const RELEASED_MAX_FOV_DEG: f64 = 220.0;

/// How to open a dataset.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OpenOptions {
    /// Unit of a released-layout folder's `poses.txt` translations (default centimetres, the
    /// released sets'); a `config.yaml`'s poses are metres and another unit is refused.
    pub pose_unit: Option<LengthUnit>,
    /// The frame the panoramas are expressed in (default: the calibration's own).
    pub frame: FrameChoice,
    /// The sweep's minimum depth, metres, instead of the dataset's (`config.yaml`'s
    /// `omnimvs_sweep_min_depth`, or [`RELEASED_MIN_DEPTH_M`] for the other layouts).
    pub min_depth_m: Option<f64>,
    /// Read the rig only: a folder without image folders opens with no frames (for images
    /// that come from elsewhere, such as a robot's live frames).
    pub rig_only: bool,
}

/// The frame a dataset's rig, and so its panoramas and point clouds, are expressed in.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RigFrame {
    /// `calibration` or `fitted`.
    pub choice: &'static str,
    /// The frame of the calibration file's poses, in words.
    pub calibration_frame: String,
    /// `frame_from_calibration` as `[rx, ry, rz, tx, ty, tz]` (rotation vector, radians;
    /// translation, metres): zeros for the calibration frame itself.
    pub frame_from_calibration: [f64; 6],
}

impl RigFrame {
    /// One line saying which frame this is.
    pub fn describe(&self) -> String {
        match self.choice {
            "fitted" => format!(
                "fitted to the cameras (origin at their mean, y normal to their plane); from {}: rotation vector ({:+.4}, {:+.4}, {:+.4}) rad, translation ({:+.4}, {:+.4}, {:+.4}) m",
                self.calibration_frame,
                self.frame_from_calibration[0],
                self.frame_from_calibration[1],
                self.frame_from_calibration[2],
                self.frame_from_calibration[3],
                self.frame_from_calibration[4],
                self.frame_from_calibration[5]
            ),
            _ => self.calibration_frame.clone(),
        }
    }
}

/// How a dataset's parts were found, for `info` and for errors.
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// The rig's file and format, e.g. `calibration.json (basalt)`.
    pub rig: String,
    /// How the frames are named, e.g. `cam0/ ... cam3/, 0.jpg (unpadded), frames found in cam0/`.
    pub images: String,
    /// Per camera: its mask files, or `field of view only`.
    pub masks: Vec<String>,
}

impl Dataset {
    /// Opens a dataset from its folder or its rig file, in the calibration's frame: a
    /// `config.yaml`; a folder without one but with `ocam1.txt` in the released datasets' layout
    /// ([`Dataset::open_released`]); or a folder with a Basalt `calibration.json` or a Kalibr
    /// `camchain.yaml` and one image folder per camera ([`OpenOptions`] for other choices).
    ///
    /// # Errors
    /// [`DataError`] naming the file and the field that is wrong.
    pub fn open(path: &Path) -> Result<Self, DataError> {
        Self::open_with(path, &OpenOptions::default())
    }

    /// Whether `path` is a folder in the released datasets' layout (no `config.yaml`, an
    /// `ocam1.txt`): what [`Dataset::open`] reads with [`Dataset::open_released`].
    pub fn is_released_layout(path: &Path) -> bool {
        path.is_dir() && !path.join("config.yaml").exists() && path.join("ocam1.txt").is_file()
    }

    /// [`Dataset::open`] with `options`.
    ///
    /// # Errors
    /// As [`Dataset::open`]; [`DataError::Field`] naming `config.yaml` when a pose unit other
    /// than metres is stated for it, or a non-positive minimum depth; a fitted frame for a rig
    /// whose cameras do not span a plane.
    pub fn open_with(path: &Path, options: &OpenOptions) -> Result<Self, DataError> {
        let mut ds = Self::open_in_calibration_frame(path, options)?;
        if let Some(min_depth_m) = options.min_depth_m {
            ds.config.min_depth_m =
                checked_min_depth(&ds.config_path, "minimum depth", min_depth_m)?;
        }
        if options.frame == FrameChoice::Fitted {
            let (rig, frame_from_calibration) = ds.rig.in_frame(options.frame)?;
            ds.rig = rig;
            ds.frame.choice = options.frame.name();
            ds.frame.frame_from_calibration =
                Pose::from_isometry(&frame_from_calibration).to_array();
        }
        Ok(ds)
    }

    fn open_in_calibration_frame(path: &Path, options: &OpenOptions) -> Result<Self, DataError> {
        if Self::is_released_layout(path) {
            return Self::open_released_in(path, options.pose_unit.unwrap_or_default());
        }
        let config_path = if path.is_dir() {
            path.join("config.yaml")
        } else {
            path.to_path_buf()
        };
        let config_yaml = if path.is_dir() {
            config_path.is_file()
        } else {
            RigFormat::detect(path)? == RigFormat::ConfigYaml
        };
        if !config_yaml {
            return Self::open_calibration(path, options);
        }
        let root = config_path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let text =
            std::fs::read_to_string(&config_path).map_err(|e| DataError::io(&config_path, e))?;
        metres_only(
            options,
            &config_path,
            "cameras[].pose",
            RigFormat::ConfigYaml,
        )?;
        let file = ConfigFile::parse(&config_path, &text)?;
        let rig = file.rig(&config_path)?;
        if file.dataset.is_none() {
            // A rig alone (`cameras:`, perhaps `config:`): the images are found by looking.
            let layout = discover(&root, rig.len(), options)?;
            let mut ds = Self::from_layout(
                &root,
                config_path.clone(),
                rig,
                RigFormat::ConfigYaml,
                &layout,
            );
            if let Some(sweep) = &file.config {
                ds.config.min_depth_m = checked_min_depth(
                    &config_path,
                    "config.omnimvs_sweep_min_depth",
                    sweep.omnimvs_sweep_min_depth,
                )?;
            }
            return Ok(ds);
        }
        let config = DatasetConfig::of_file(&config_path, &file)?;
        let images = format!(
            "{} (dataset.img_fmt), frames {} (dataset.start/step/end)",
            config.img_fmt, config.frames
        );
        Ok(Self::assemble(
            root,
            config_path,
            config,
            rig,
            1,
            RigFormat::ConfigYaml,
            images,
        ))
    }

    /// Opens a folder in the layout the released datasets were published in: `ocam1.txt` ...
    /// `ocamN.txt` (OCamCalib's text form) and `poses.txt` (translation in centimetres) for the
    /// rig, the cameras' fields of view [`RELEASED_MAX_FOV_DEG`], the images in `cam1/` ...
    /// (`00001.png` or `0001.png`, any image extension; the frames are those found in
    /// `cam1/`), ground truth in `omnidepth_gt_640/` or `depth_train_640/` when present, and
    /// the minimum depth [`RELEASED_MIN_DEPTH_M`]. Nothing is written into the folder.
    ///
    /// # Errors
    /// [`DataError`] naming the file: a missing or malformed `ocamK.txt` or `poses.txt`, or a
    /// `cam1/` folder without numbered images.
    pub fn open_released(dir: &Path) -> Result<Self, DataError> {
        Self::open_released_in(dir, LengthUnit::Centimetre)
    }

    /// [`Dataset::open_released`] with the translations of `poses.txt` in `pose_unit`
    /// (millimetres in SweepNet's `real_indoor_sample`, for one).
    ///
    /// # Errors
    /// As [`Dataset::open_released`].
    pub fn open_released_in(dir: &Path, pose_unit: LengthUnit) -> Result<Self, DataError> {
        let rig = omnimvs_camera::read_ocam_txt_rig_in(dir, RELEASED_MAX_FOV_DEG, pose_unit)?;
        let (naming, frames) = crate::layout::frame_naming(&dir.join("cam1"))?;
        Ok(Self::from_layout(
            dir,
            dir.join("poses.txt"),
            rig,
            RigFormat::OcamTxt,
            &ImageLayout {
                first_camera_number: 1,
                img_fmt: format!("cam%d/{naming}"),
                frames,
            },
        ))
    }

    /// Opens a folder with a calibration tool's rig file (or that file) and one image folder
    /// per camera beside it ([`ImageLayout::discover`]): frames as found in the first camera's
    /// folder, masks beside the images, the minimum depth [`RELEASED_MIN_DEPTH_M`] unless stated.
    ///
    /// # Errors
    /// The rig file's errors ([`omnimvs_camera::read_rig_file`]); missing camera folders or
    /// images; a pose unit stated for a file whose translations are metres.
    fn open_calibration(path: &Path, options: &OpenOptions) -> Result<Self, DataError> {
        let (rig, format, file) = omnimvs_camera::read_rig_file(path)?;
        metres_only(options, &file, "poses", format)?;
        let root = file.parent().map(Path::to_path_buf).unwrap_or_default();
        let layout = discover(&root, rig.len(), options)?;
        Ok(Self::from_layout(&root, file, rig, format, &layout))
    }

    /// A dataset whose images were found by looking ([`ImageLayout`]); masks beside the images
    /// join the cameras.
    fn from_layout(
        root: &Path,
        config_path: PathBuf,
        rig: Rig,
        format: RigFormat,
        layout: &ImageLayout,
    ) -> Self {
        let first = layout.frames.first().copied().unwrap_or(0);
        let last = layout.frames.last().copied().unwrap_or(0);
        let config = DatasetConfig {
            min_depth_m: RELEASED_MIN_DEPTH_M,
            img_fmt: layout.img_fmt.clone(),
            frames: FrameRange::inclusive(first, last),
            gt_fmt: None,
            split: None,
        };
        let n = layout.first_camera_number;
        let images = format!(
            "{} with cameras numbered from {n}, {} frames found in cam{n}/ ({first}..{last})",
            layout.img_fmt,
            layout.frames.len()
        );
        Self::assemble(
            root.to_path_buf(),
            config_path,
            config,
            rig,
            n,
            format,
            images,
        )
    }

    /// The dataset with its masks found beside the images and the calibration's frame.
    fn assemble(
        root: PathBuf,
        config_path: PathBuf,
        config: DatasetConfig,
        rig: Rig,
        first_camera_number: u32,
        format: RigFormat,
        images: String,
    ) -> Self {
        let mut rig = rig;
        let mut masks = Vec::with_capacity(rig.len());
        for (i, cam) in rig.cameras.iter_mut().enumerate() {
            let number = i64::from(first_camera_number) + i as i64;
            let image_dir = format_printf(&config.img_fmt, &[number, 0])
                .and_then(|p| Path::new(&p).parent().map(Path::to_path_buf));
            if cam.valid_mask.is_none()
                && let Some(dir) = image_dir
            {
                cam.valid_mask = mask_beside(&root, &dir);
            }
            let mut found = Vec::new();
            if let Some(m) = &cam.invalid_mask
                && root.join(m).is_file()
            {
                found.push(format!("{m} (invalid_mask: nonzero = invalid)"));
            }
            if let Some(m) = &cam.valid_mask {
                found.push(format!("{m} (beside the images: nonzero = valid)"));
            }
            masks.push(if found.is_empty() {
                "field of view only".to_string()
            } else {
                found.join(", ")
            });
        }
        let file_name = config_path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        Self {
            root,
            config_path,
            config,
            rig,
            first_camera_number,
            frame: RigFrame {
                choice: FrameChoice::Calibration.name(),
                calibration_frame: format.rig_frame().to_string(),
                frame_from_calibration: [0.0; 6],
            },
            found: Found {
                rig: format!("{file_name} ({})", format.name()),
                images,
                masks,
            },
        }
    }
}

/// A minimum depth, checked positive; `path` and `field` name where it came from in the error.
fn checked_min_depth(path: &Path, field: &str, min_depth_m: f64) -> Result<f64, DataError> {
    if min_depth_m.is_finite() && min_depth_m > 0.0 {
        Ok(min_depth_m)
    } else {
        Err(DataError::Field {
            path: path.to_path_buf(),
            field: field.into(),
            message: format!("expected a positive depth in metres, found {min_depth_m}"),
        })
    }
}

/// [`ImageLayout::discover`]; with [`OpenOptions::rig_only`], a folder without images gives the
/// layout `cam%d/%05d.png` from camera 1 with no frames.
fn discover(
    root: &Path,
    num_cameras: usize,
    options: &OpenOptions,
) -> Result<ImageLayout, DataError> {
    match ImageLayout::discover(root, num_cameras) {
        Err(_) if options.rig_only => Ok(ImageLayout {
            first_camera_number: 1,
            img_fmt: "cam%d/%05d.png".into(),
            frames: Vec::new(),
        }),
        found => found,
    }
}

/// Refuses a pose unit other than metres for a rig file whose translations are metres (every
/// format but the released layout's `poses.txt`); `path` and `field` name them in the error.
fn metres_only(
    options: &OpenOptions,
    path: &Path,
    field: &str,
    format: RigFormat,
) -> Result<(), DataError> {
    match options.pose_unit {
        Some(unit) if unit != LengthUnit::Metre => Err(DataError::Field {
            path: path.to_path_buf(),
            field: field.into(),
            message: format!(
                "a {} file's translations are metres (as the reference reads them), not {unit}: a pose unit applies to a released-layout folder's poses.txt",
                format.name()
            ),
        }),
        _ => Ok(()),
    }
}
