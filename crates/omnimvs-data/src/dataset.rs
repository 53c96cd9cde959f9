use std::path::{Path, PathBuf};

use omnimvs_camera::{ConfigFile, Rig, ValidityMask};
use omnimvs_core::GrayImage;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, SweepSpec};
use rayon::prelude::*;

use crate::gt::{EvalTruth, GroundTruth, InvDepthMap, eval_truth_on_grid, read_inv_depth};
use crate::image_io::read_gray_sized;
use crate::{DataError, DatasetConfig, format_printf};

/// A dataset folder in the reference layout. Opening it reads only
/// `config.yaml`; nothing is ever written into the folder.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub root: PathBuf,
    pub config_path: PathBuf,
    pub config: DatasetConfig,
    pub rig: Rig,
}

/// Folders and extensions searched for ground truth when `dataset.gt_fmt`
/// is not set, in order.
const GT_DIRS: [&str; 2] = ["omnidepth_gt_640", "depth_train_640"];
const GT_EXTS: [&str; 5] = ["tiff", "tif", "png", "bin", "raw"];

/// Minimum depth of the released datasets (OmniThings, OmniHouse, the urban sets), metres: their
/// 16-bit ground truth encodes inverse depth relative to `1 / 0.55`.
pub const RELEASED_MIN_DEPTH_M: f64 = 0.55;

/// Field of view of the released rigs' cameras, degrees (their text files do not carry it).
pub const RELEASED_MAX_FOV_DEG: f64 = 220.0;

impl Dataset {
    /// Opens a dataset from its folder or its `config.yaml`. A folder without `config.yaml`
    /// but with `ocam1.txt` is read in the released datasets' layout (see
    /// [`Dataset::open_released`]).
    ///
    /// # Errors
    /// [`DataError`] naming `config.yaml` and the field that is wrong.
    pub fn open(path: &Path) -> Result<Self, DataError> {
        Self::open_with(path, None)
    }

    /// Whether `path` is a folder in the released datasets' layout (no `config.yaml`, an
    /// `ocam1.txt`): what [`Dataset::open`] reads with [`Dataset::open_released`].
    pub fn is_released_layout(path: &Path) -> bool {
        path.is_dir() && !path.join("config.yaml").exists() && path.join("ocam1.txt").is_file()
    }

    /// [`Dataset::open`], the translations of a released-layout folder's `poses.txt` read in
    /// `pose_unit` (default centimetres, the released sets' unit). A `config.yaml`'s poses are
    /// metres, as the reference implementation reads them: another unit stated for one is an
    /// error rather than a silent rescaling.
    ///
    /// # Errors
    /// As [`Dataset::open`]; [`DataError::Field`] naming `config.yaml` when `pose_unit` is not
    /// metres for a `config.yaml` dataset.
    pub fn open_with(
        path: &Path,
        pose_unit: Option<omnimvs_camera::LengthUnit>,
    ) -> Result<Self, DataError> {
        if Self::is_released_layout(path) {
            return Self::open_released_in(path, pose_unit.unwrap_or_default());
        }
        let (root, config_path) = if path.is_dir() {
            (path.to_path_buf(), path.join("config.yaml"))
        } else {
            let root = path.parent().map(Path::to_path_buf).unwrap_or_default();
            (root, path.to_path_buf())
        };
        let text =
            std::fs::read_to_string(&config_path).map_err(|e| DataError::io(&config_path, e))?;
        if let Some(unit) = pose_unit
            && unit != omnimvs_camera::LengthUnit::Metre
        {
            return Err(DataError::Field {
                path: config_path,
                field: "cameras[].pose".into(),
                message: format!(
                    "a config.yaml's translations are metres (as the reference reads them), not {unit}: a pose unit applies to a released-layout folder's poses.txt"
                ),
            });
        }
        let file = ConfigFile::parse(&config_path, &text)?;
        let rig = file.rig(&config_path)?;
        let config = DatasetConfig::of_file(&config_path, &file)?;
        Ok(Self {
            root,
            config_path,
            config,
            rig,
        })
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
        Self::open_released_in(dir, omnimvs_camera::LengthUnit::Centimetre)
    }

    /// [`Dataset::open_released`] with the translations of `poses.txt` in `pose_unit`
    /// (millimetres in SweepNet's `real_indoor_sample`, for one).
    ///
    /// # Errors
    /// As [`Dataset::open_released`].
    pub fn open_released_in(
        dir: &Path,
        pose_unit: omnimvs_camera::LengthUnit,
    ) -> Result<Self, DataError> {
        let rig = omnimvs_camera::read_ocam_txt_rig_in(dir, RELEASED_MAX_FOV_DEG, pose_unit)?;
        let cam_dir = dir.join("cam1");
        let entries = std::fs::read_dir(&cam_dir).map_err(|e| DataError::io(&cam_dir, e))?;
        // (digits, extension) -> frames found with that naming.
        let mut namings: std::collections::BTreeMap<(usize, String), Vec<u32>> =
            std::collections::BTreeMap::new();
        for entry in entries {
            let path = entry.map_err(|e| DataError::io(&cam_dir, e))?.path();
            let (Some(stem), Some(ext)) = (
                path.file_stem().and_then(|s| s.to_str()),
                path.extension().and_then(|s| s.to_str()),
            ) else {
                continue;
            };
            let image = ["png", "jpg", "jpeg", "bmp", "tif", "tiff"]
                .contains(&ext.to_ascii_lowercase().as_str());
            if let (true, true, Ok(frame)) = (
                image,
                stem.bytes().all(|b| b.is_ascii_digit()),
                stem.parse::<u32>(),
            ) {
                namings
                    .entry((stem.len(), ext.to_string()))
                    .or_default()
                    .push(frame);
            }
        }
        let Some(((digits, ext), frames)) = namings.into_iter().max_by_key(|(_, f)| f.len()) else {
            return Err(DataError::format(
                &cam_dir,
                "no numbered images (such as 00001.png) in the first camera's folder",
            ));
        };
        let (first, last) = frames
            .iter()
            .fold((u32::MAX, 0), |(a, b), &f| (a.min(f), b.max(f)));
        Ok(Self {
            root: dir.to_path_buf(),
            config_path: dir.join("poses.txt"),
            config: DatasetConfig {
                min_depth_m: RELEASED_MIN_DEPTH_M,
                img_fmt: format!("cam%d/%0{digits}d.{ext}"),
                frames: crate::FrameRange::inclusive(first, last),
                gt_fmt: None,
                split: None,
            },
            rig,
        })
    }

    /// The hypotheses of this dataset for `ndepth` spheres.
    ///
    /// # Errors
    /// [`DataError::Sweep`] for `ndepth < 2`.
    pub fn hypotheses(&self, ndepth: usize) -> Result<InvDepthHypotheses, DataError> {
        Ok(InvDepthHypotheses::new(ndepth, self.config.min_depth_m)?)
    }

    /// The sweep of this dataset on a `height x width` grid over `±phi_deg` with `ndepth`
    /// spheres from the configuration's minimum depth.
    ///
    /// # Errors
    /// [`DataError::Sweep`] for a grid or `ndepth` out of range.
    pub fn sweep_spec(
        &self,
        height: usize,
        width: usize,
        phi_deg: f64,
        ndepth: usize,
    ) -> Result<SweepSpec, DataError> {
        Ok(SweepSpec::from_sizes(
            height,
            width,
            phi_deg,
            ndepth,
            self.config.min_depth_m,
        )?)
    }

    /// Candidate paths of an image: the configured pattern, then the same
    /// with the frame number zero-padded to 4 and 5 digits (released sets mix
    /// `0001.png` and `00001.png`).
    fn image_candidates(&self, camera: usize, frame: u32) -> Vec<PathBuf> {
        let fmt = &self.config.img_fmt;
        let mut out = Vec::new();
        let args = [camera as i64 + 1, i64::from(frame)];
        if let Some(p) = format_printf(fmt, &args) {
            out.push(self.root.join(p));
        }
        // Replace the frame conversion (the last `%...d`) with other paddings.
        if let Some(pos) = fmt.rfind('%') {
            let tail = fmt[pos..].find('d').map(|k| pos + k + 1);
            if let Some(end) = tail {
                for alt in ["%04d", "%05d", "%d"] {
                    let f = format!("{}{}{}", &fmt[..pos], alt, &fmt[end..]);
                    if let Some(p) = format_printf(&f, &args) {
                        let p = self.root.join(p);
                        if !out.contains(&p) {
                            out.push(p);
                        }
                    }
                }
            }
        }
        out
    }

    /// The existing image file of `camera` (0-based) at `frame`.
    ///
    /// # Errors
    /// [`DataError::MissingFrame`] listing the paths tried.
    pub fn image_path(&self, camera: usize, frame: u32) -> Result<PathBuf, DataError> {
        let candidates = self.image_candidates(camera, frame);
        candidates
            .iter()
            .find(|p| p.is_file())
            .cloned()
            .ok_or_else(|| DataError::MissingFrame {
                frame,
                camera: camera + 1,
                tried: candidates
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// Whether every camera has an image for `frame`.
    pub fn has_frame(&self, frame: u32) -> bool {
        (0..self.rig.len()).all(|c| self.image_path(c, frame).is_ok())
    }

    /// The frames of the configured range whose images all exist.
    pub fn frames_found(&self) -> Vec<u32> {
        self.config
            .frames
            .indices()
            .into_iter()
            .filter(|&f| self.has_frame(f))
            .collect()
    }

    /// The gray image of `camera` (0-based) at `frame`, size-checked.
    ///
    /// # Errors
    /// Missing or corrupt file, or a size that differs from the camera's.
    pub fn read_image(&self, camera: usize, frame: u32) -> Result<GrayImage, DataError> {
        let path = self.image_path(camera, frame)?;
        let model = &self.rig.cameras[camera].model;
        read_gray_sized(
            &path,
            model.width() as usize,
            model.height() as usize,
            &format!(
                "camera {} image_size in {}",
                camera + 1,
                self.config_path.display()
            ),
        )
    }

    /// The gray images of every camera at `frame`.
    ///
    /// # Errors
    /// As [`Self::read_image`].
    pub fn read_frame(&self, frame: u32) -> Result<Vec<GrayImage>, DataError> {
        (0..self.rig.len())
            .map(|c| self.read_image(c, frame))
            .collect()
    }

    /// The validity mask of every camera (the cameras in parallel: each unprojects every
    /// pixel of its image, a fifth of `infer`'s start-up when one after the other).
    ///
    /// # Errors
    /// A mask PNG that exists but is corrupt or of the wrong size.
    pub fn masks(&self) -> Result<Vec<ValidityMask>, DataError> {
        self.rig
            .cameras
            .par_iter()
            .map(|c| ValidityMask::for_camera(c, &self.root).map_err(DataError::from))
            .collect()
    }

    /// The ground-truth file of `frame`, if there is one.
    pub fn gt_path(&self, frame: u32) -> Option<PathBuf> {
        if let Some(fmt) = &self.config.gt_fmt {
            let p = self.root.join(format_printf(fmt, &[i64::from(frame)])?);
            return p.is_file().then_some(p);
        }
        for dir in GT_DIRS {
            for digits in [5usize, 4] {
                for ext in GT_EXTS {
                    let p = self.root.join(dir).join(format!("{frame:0digits$}.{ext}"));
                    if p.is_file() {
                        return Some(p);
                    }
                }
            }
        }
        None
    }

    /// The ground-truth inverse depth of `frame` (full height), if present.
    ///
    /// # Errors
    /// A ground-truth file that exists but cannot be read.
    pub fn read_gt(&self, frame: u32) -> Result<Option<InvDepthMap>, DataError> {
        self.gt_path(frame).map(|p| read_inv_depth(&p)).transpose()
    }

    /// The ground truth of `frame` as indices on the rays of the output `grid`, for `hyps`,
    /// masked as for evaluation. A grid at the ground truth's own width with square pixels
    /// (`phi_deg = 180 height / width`) gets the middle rows cropped, exactly as the
    /// reference does; any other grid (a smaller network grid, another latitude range)
    /// samples the indices and the validity, computed at full resolution, at its rays
    /// ([`crate::gt::sample_ground_truth`]). Sky is valid at index 0 (the ground truth of training and
    /// of the `with-sky` protocol); [`Self::eval_truth`] adds the sky mask.
    ///
    /// # Errors
    /// An unreadable file, or a grid that reaches beyond the map's latitudes.
    pub fn ground_truth(
        &self,
        frame: u32,
        grid: &EquirectGrid,
        hyps: &InvDepthHypotheses,
    ) -> Result<Option<GroundTruth>, DataError> {
        let spec = SweepSpec::new(*grid, *hyps);
        Ok(self.eval_truth(frame, &spec)?.map(|truth| truth.gt))
    }

    /// [`Self::ground_truth`] on `spec`'s grid and hypotheses together with the sky mask on
    /// the same pixels, for scoring under either protocol (`omnimvs_eval::metrics::Protocol`;
    /// [`eval_truth_on_grid`]).
    ///
    /// # Errors
    /// As [`Self::ground_truth`].
    pub fn eval_truth(&self, frame: u32, spec: &SweepSpec) -> Result<Option<EvalTruth>, DataError> {
        let (grid, hyps) = (&spec.grid, &spec.hypotheses);
        let Some(map) = self.read_gt(frame)? else {
            return Ok(None);
        };
        if grid.phi_deg > map.phi_deg() + 1e-9 {
            return Err(DataError::mismatch(
                format!("frame {frame} ground-truth latitude range"),
                format!(
                    "at least ±{} degrees (a {}x{} output)",
                    grid.phi_deg, grid.height, grid.width
                ),
                format!("±{} degrees", map.phi_deg()),
            ));
        }
        Ok(Some(eval_truth_on_grid(&map, hyps, grid)?))
    }
}
