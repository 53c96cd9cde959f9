//! One training sample: the network inputs of a frame and its ground truth, read from a
//! dataset folder for one of the precomputed rig rotations.

use std::path::Path;

use omnimvs_camera::ValidityMask;
use omnimvs_data::Dataset;
use omnimvs_data::gt::GroundTruth;
use omnimvs_sweep::{EquirectGrid, GrayImage, InvDepthHypotheses};

use super::augment::{RotationSet, resample_ground_truth, rotated_grids};
use crate::config::NetConfig;
use crate::error::NetError;
use crate::infer::{network_inputs, sweep_geometry};
use crate::taps::SweepGrid;

/// A prepared sample.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Which source (dataset) it comes from.
    pub source: usize,
    /// Frame index.
    pub frame: u32,
    /// Index of the rig rotation in the source's [`RotationSet`].
    pub rotation: usize,
    /// Network input of every camera (rig order): `input_height x input_width`, normalised
    /// over the camera's valid pixels.
    pub images: Vec<Vec<f32>>,
    /// Ground truth on the output grid, rotated with the rig.
    pub gt: GroundTruth,
}

/// A dataset prepared for training: its rig, masks, hypotheses and the sweep grids of every
/// rotation of the augmentation.
pub struct SampleSource {
    /// The dataset.
    pub dataset: Dataset,
    /// Validity masks at the dataset's image size.
    pub masks: Vec<ValidityMask>,
    /// The `N` hypotheses.
    pub hypotheses: InvDepthHypotheses,
    /// The output grid.
    pub grid: EquirectGrid,
    /// The rotations of the augmentation (identity first).
    pub rotations: RotationSet,
    /// `grids[rotation][camera]`.
    pub grids: Vec<Vec<SweepGrid>>,
    /// Network input size `[rows, cols]`.
    pub input_size: [usize; 2],
}

impl SampleSource {
    /// Opens `path` and builds the sweep grids of every rotation for `net`.
    ///
    /// # Errors
    /// [`NetError`] when the dataset cannot be read or its rig does not fit the network.
    pub fn open(path: &Path, net: &NetConfig, rotations: RotationSet) -> Result<Self, NetError> {
        let dataset = Dataset::open(path)?;
        let (grid, hypotheses) = sweep_geometry(net, &dataset)?;
        let grids = rotations
            .rotations
            .iter()
            .map(|r| rotated_grids(&dataset.rig, r, &grid, &hypotheses))
            .collect::<Result<Vec<_>, _>>()?;
        let masks = dataset.masks()?;
        Ok(Self {
            dataset,
            masks,
            hypotheses,
            grid,
            rotations,
            grids,
            input_size: [net.input_height, net.input_width],
        })
    }

    /// Frames of the dataset that have ground truth.
    pub fn frames_with_gt(&self) -> Vec<u32> {
        self.dataset
            .frames_found()
            .into_iter()
            .filter(|&f| self.dataset.gt_path(f).is_some())
            .collect()
    }

    /// Network inputs of a frame's gray images: normalised over the valid pixels, resized.
    ///
    /// # Errors
    /// [`NetError`] for a mask of another size.
    pub fn inputs(&self, images: &[GrayImage]) -> Result<Vec<Vec<f32>>, NetError> {
        network_inputs(images, &self.masks, self.input_size)
    }

    /// Reads `frame` for rotation `rotation` (`source` is only recorded in the sample).
    ///
    /// # Errors
    /// [`NetError`] when a file is missing or unreadable, or the frame has no ground truth.
    pub fn load(&self, source: usize, frame: u32, rotation: usize) -> Result<Sample, NetError> {
        let images = self.dataset.read_frame(frame)?;
        let images = self.inputs(&images)?;
        let map =
            self.dataset
                .read_gt(frame)?
                .ok_or_else(|| omnimvs_data::DataError::Mismatch {
                    what: format!(
                        "{}: ground truth of frame {frame}",
                        self.dataset.root.display()
                    ),
                    expected: "a ground-truth file".into(),
                    found: "none".into(),
                })?;
        let gt = resample_ground_truth(
            &map,
            &self.grid,
            &self.rotations.rotations[rotation],
            &self.hypotheses,
        )?;
        Ok(Sample {
            source,
            frame,
            rotation,
            images,
            gt,
        })
    }
}
