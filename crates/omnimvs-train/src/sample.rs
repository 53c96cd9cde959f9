//! One training sample: the network inputs of a frame and its ground truth, read from a
//! dataset folder for one of the precomputed rig rotations.

use std::path::Path;

use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_camera::ValidityMask;
use omnimvs_core::GrayImage;
use omnimvs_data::Dataset;
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::cascade::ColumnWindow;
use omnimvs_net::config::{Family, NetConfig};
use omnimvs_net::infer::{network_inputs, sweep_geometry};
use omnimvs_net::taps::SweepGrid;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};

use crate::augment::{RotationSet, resample_ground_truth, rotate_rig, rotated_grids};
use crate::error::TrainError;
use crate::photometric::PhotometricAugment;

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
    /// Ground truth on the grids of the network's earlier stages (the cascade's coarse and
    /// half-resolution grids; empty for the paper's network), rotated likewise.
    pub stage_gt: Vec<GroundTruth>,
    /// The window of longitudes the cascade's refinement stages train on (`None`: the whole
    /// panorama; the paper's network ignores it).
    pub window: Option<ColumnWindow>,
}

impl Sample {
    /// The images as `[1, 1, rows, cols]` tensors on `device` (`[rows, cols]` the network's
    /// input size, the size the images were prepared at).
    pub fn image_tensors(&self, [rows, cols]: [usize; 2], device: &Device) -> Vec<Tensor<4>> {
        self.images
            .iter()
            .map(|image| {
                Tensor::from_data(TensorData::new(image.clone(), [1, 1, rows, cols]), device)
            })
            .collect()
    }
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
    /// The paper's network's lookup tables, `grids[rotation][camera]` (empty for the
    /// cascade, which projects on the fly).
    pub grids: Vec<Vec<SweepGrid>>,
    /// Grids of the earlier stages whose ground truth a sample carries.
    pub stage_grids: Vec<EquirectGrid>,
    /// Network input size `[rows, cols]`.
    pub input_size: [usize; 2],
}

impl SampleSource {
    /// Opens `path` and builds the sweep grids of every rotation for `net`.
    ///
    /// # Errors
    /// [`TrainError`] when the dataset cannot be read or its rig does not fit the network.
    pub fn open(path: &Path, net: &NetConfig, rotations: RotationSet) -> Result<Self, TrainError> {
        let dataset = Dataset::open(path)?;
        let (grid, hypotheses) = sweep_geometry(net, &dataset)?;
        let (grids, stage_grids) = match net.family {
            Family::OmniMvs => (
                rotations
                    .rotations
                    .iter()
                    .map(|r| rotated_grids(&dataset.rig, r, &grid, &hypotheses))
                    .collect::<Result<Vec<_>, _>>()?,
                Vec::new(),
            ),
            Family::Cascade => {
                let [coarse, mid, _] = net.cascade_sizes();
                let stage_grids = [coarse, mid]
                    .into_iter()
                    .map(|[h, w]| EquirectGrid::new(h, w, net.phi_deg))
                    .collect::<Result<Vec<_>, _>>()?;
                (Vec::new(), stage_grids)
            }
        };
        let masks = dataset.masks()?;
        Ok(Self {
            dataset,
            masks,
            hypotheses,
            grid,
            rotations,
            grids,
            stage_grids,
            input_size: [net.input_height, net.input_width],
        })
    }

    /// The rig seen in the frame of rotation `rotation`.
    pub fn rotated_rig(&self, rotation: usize) -> omnimvs_camera::Rig {
        rotate_rig(&self.dataset.rig, &self.rotations.rotations[rotation])
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
    /// [`TrainError`] for a mask of another size.
    pub fn inputs(&self, images: &[GrayImage]) -> Result<Vec<Vec<f32>>, TrainError> {
        Ok(network_inputs(images, &self.masks, self.input_size)?)
    }

    /// Reads `frame` for rotation `rotation` (`source` is only recorded in the sample), its
    /// images changed by `photometric` with the given seed when one is given.
    ///
    /// # Errors
    /// [`TrainError`] when a file is missing or unreadable, or the frame has no ground truth.
    pub fn load(
        &self,
        source: usize,
        frame: u32,
        rotation: usize,
        photometric: Option<(&PhotometricAugment, u64)>,
    ) -> Result<Sample, TrainError> {
        let mut images = self.dataset.read_frame(frame)?;
        if let Some((augment, seed)) = photometric {
            augment.apply(&mut images, seed);
        }
        let images = self.inputs(&images)?;
        let map = self.dataset.read_gt(frame)?.ok_or_else(|| {
            omnimvs_sweep::SweepError::mismatch(
                format!(
                    "{}: ground truth of frame {frame}",
                    self.dataset.root.display()
                ),
                "a ground-truth file",
                "none",
            )
        })?;
        let rotation_matrix = &self.rotations.rotations[rotation];
        let gt = resample_ground_truth(&map, &self.grid, rotation_matrix, &self.hypotheses)?;
        let stage_gt = self
            .stage_grids
            .iter()
            .map(|grid| resample_ground_truth(&map, grid, rotation_matrix, &self.hypotheses))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Sample {
            source,
            frame,
            rotation,
            images,
            gt,
            stage_gt,
            window: None,
        })
    }
}
