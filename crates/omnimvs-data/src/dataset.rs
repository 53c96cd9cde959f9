use std::path::PathBuf;

use omnimvs_camera::{Rig, ValidityMask};
use omnimvs_core::{ColourPlanes, GrayImage};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, SweepSpec};
use rayon::prelude::*;

use crate::gt::{EvalTruth, GroundTruth, InvDepthMap, eval_truth_on_grid, read_inv_depth};
use crate::image_io::{DecodedImage, colour_of_frame, read_decoded_sized};
use crate::open::{Found, RigFrame};
use crate::{DataError, DatasetConfig, format_printf};

/// A dataset folder: its rig, the sweep's minimum depth, where its images and ground truth
/// are. Opening it ([`crate::OpenOptions`]) reads the rig file and lists the first camera's
/// folder; nothing is ever written into the folder.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub root: PathBuf,
    pub config_path: PathBuf,
    pub config: DatasetConfig,
    pub rig: Rig,
    /// The number in the first camera's folder name and in `img_fmt` (1 in `config.yaml`
    /// and the released layout, 0 or 1 in a calibration-file folder).
    pub first_camera_number: u32,
    /// The frame the rig, and so every panorama and point cloud, is expressed in.
    pub frame: RigFrame,
    /// How the rig, the images and the masks were found.
    pub found: Found,
}

/// Folders and extensions searched for ground truth when `dataset.gt_fmt`
/// is not set, in order.
const GT_DIRS: [&str; 2] = ["omnidepth_gt_640", "depth_train_640"];
const GT_EXTS: [&str; 5] = ["tiff", "tif", "png", "bin", "raw"];

impl Dataset {
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
        let args = [
            i64::from(self.first_camera_number) + camera as i64,
            i64::from(frame),
        ];
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
        Ok(self.read_decoded_image(camera, frame, false)?.gray)
    }

    /// The image of `camera` (0-based) at `frame` decoded once, size-checked: gray and, when
    /// `colour` is asked and the file has colour channels, its colour planes.
    ///
    /// # Errors
    /// As [`Self::read_image`].
    pub fn read_decoded_image(
        &self,
        camera: usize,
        frame: u32,
        colour: bool,
    ) -> Result<DecodedImage, DataError> {
        let path = self.image_path(camera, frame)?;
        let model = &self.rig.cameras[camera].model;
        read_decoded_sized(
            &path,
            colour,
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

    /// The images of every camera at `frame`, each decoded once as gray and, when the file
    /// has colour channels, as colour.
    ///
    /// # Errors
    /// As [`Self::read_image`].
    pub fn read_decoded_frame(&self, frame: u32) -> Result<Vec<DecodedImage>, DataError> {
        (0..self.rig.len())
            .map(|c| self.read_decoded_image(c, frame, true))
            .collect()
    }

    /// The gray images of every camera at `frame` and, when any of them is in colour, the
    /// colour images of every camera ([`colour_of_frame`]); each file decoded once.
    ///
    /// # Errors
    /// As [`Self::read_image`].
    pub fn read_frame_and_colour(
        &self,
        frame: u32,
    ) -> Result<(Vec<GrayImage>, Option<Vec<ColourPlanes>>), DataError> {
        let decoded = self.read_decoded_frame(frame)?;
        let colour = colour_of_frame(&decoded);
        Ok((decoded.into_iter().map(|d| d.gray).collect(), colour))
    }

    /// The colour images of every camera at `frame`, `None` when every image of the frame is
    /// single-channel ([`colour_of_frame`]).
    ///
    /// # Errors
    /// As [`Self::read_image`].
    pub fn read_colour_frame(&self, frame: u32) -> Result<Option<Vec<ColourPlanes>>, DataError> {
        Ok(colour_of_frame(&self.read_decoded_frame(frame)?))
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
