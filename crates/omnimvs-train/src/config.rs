//! The training configuration: nests the network's sizes, the optimiser and the data
//! split; written as `train_config.json` in every run folder and read back by `--resume`.

use std::ops::RangeInclusive;
use std::path::PathBuf;

use omnimvs_net::config::{Family, NetConfig};
use serde::{Deserialize, Serialize};

use crate::error::TrainError;
use crate::photometric::PhotometricAugment;

/// The optimiser of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Optimizer {
    /// SGD with momentum (the paper's).
    #[default]
    Sgd,
    /// Adam (`momentum` is its `beta_1`): converges in far fewer steps, which is what a CPU
    /// budget of a few thousand steps needs.
    Adam,
}

/// Which validation protocol decides the best epoch (`best.safetensors`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Selection {
    /// MAE with sky scored as index 0 (`val` in `metrics.jsonl`, what training asks for).
    #[default]
    WithSky,
    /// MAE under the reference's protocol, sky not scored (`val_reference`, the paper's
    /// tables).
    Reference,
}

/// Which of the network's weights a run trains.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrainParts {
    /// Every weight.
    #[default]
    All,
    /// The cascade's learnt upsampling selectors only (`convex_upsampling`); every other weight
    /// and every batch-norm statistic stays as loaded.
    Upsampling,
    /// The cascade's coarse stage only: the stride-8 branch of the feature pyramid (after
    /// the stride-4 features) and the coarse regulariser. Its loss is the coarse stage's
    /// alone, so a step runs no refinement stage: about twice as many steps in the same
    /// time. The stride-2 and stride-4 features, the refinement stages and the selectors stay
    /// as loaded, so the refinement reads the features it was trained on.
    Coarse,
    /// The cascade's half-resolution stage only (its regulariser); every other weight and
    /// every batch-norm statistic stays as loaded. Its loss is the whole network's, of which
    /// only the half stage's terms reach it (each stage's hypotheses are built from the
    /// previous answer without a gradient).
    Mid,
    /// The cascade's full-resolution stage only: its regulariser and the projection of the
    /// stride-2 features it alone reads (`out2`); every other weight and every batch-norm
    /// statistic stays as loaded. Its loss is the whole network's, of which only the full
    /// stage's terms reach it.
    Fine,
}

/// Everything that decides a training run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainConfig {
    /// The network's sizes.
    pub net: NetConfig,
    /// Dataset folders (reference layout with `omnidepth_gt_640` ground truth).
    pub data: Vec<PathBuf>,
    /// Frames used for training, inclusive; `None`: every frame found outside `val_frames`.
    pub train_frames: Option<(u32, u32)>,
    /// Frames used for validation, inclusive; `None`: the last `val_fraction` of the frames
    /// found in each dataset.
    pub val_frames: Option<(u32, u32)>,
    /// Share of the frames held out for validation when `val_frames` is not given.
    pub val_fraction: f64,
    /// Number of epochs.
    pub epochs: usize,
    /// Learning rate of the first epochs (0.003 in the paper).
    pub lr: f64,
    /// Learning rate of the last `low_lr_epochs` epochs (0.0003 in the paper).
    pub lr_low: f64,
    /// Epochs at `lr_low`; `None`: the last third (`epochs / 3`).
    pub low_lr_epochs: Option<usize>,
    /// The optimiser (absent in older runs: SGD).
    pub optimizer: Optimizer,
    /// SGD momentum (Adam's `beta_1`).
    pub momentum: f64,
    /// L2 weight decay (0 in the paper).
    pub weight_decay: f64,
    /// Seed of the initial weights, the shuffling and the augmentations.
    pub seed: u64,
    /// Number of rig rotations precomputed for augmentation, the identity included; 1 turns
    /// the rotation augmentation off.
    pub rotations: usize,
    /// Largest rotation angle of the augmentation, degrees.
    pub max_rotation_deg: f64,
    /// Whether the camera order at the concatenation is cyclically shifted at random.
    pub permute_cameras: bool,
    /// Training steps per epoch at most (`None`: every training frame once).
    pub max_steps_per_epoch: Option<usize>,
    /// Validation frames per epoch at most (`None`: all of them).
    pub max_val_frames: Option<usize>,
    /// Samples prepared ahead by the loader threads.
    pub prefetch: usize,
    /// Threads preparing the samples (absent in older runs: 1). The samples and their order
    /// do not depend on it; a GPU's steps outrun one thread.
    #[serde(default = "one_thread", skip_serializing_if = "is_one_thread")]
    pub loader_threads: usize,
    /// Weights the run started from (`--init`, fine-tuning), if any.
    pub init: Option<PathBuf>,
    /// Columns (of the output grid) of the window of longitudes the cascade's refinement
    /// stages train on, at a random even start every step (`None`: the whole panorama).
    pub column_window: Option<usize>,
    /// Per-camera photometric augmentation (exposure, gamma, vignetting, blur, noise) of the
    /// training images (`None`: the rendered images as they are; absent in older runs).
    pub photometric: Option<PhotometricAugment>,
    /// Batch norms keep their running statistics during training and normalise with them, as
    /// at inference (their scale and shift still learn). Fine-tuning with one sample a step
    /// wants this: batch statistics of one augmented window, and running statistics that
    /// follow the last few of them, moved validation more than the weights did (absent in
    /// older runs: off).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub frozen_norm_stats: bool,
    /// The protocol whose validation MAE picks `best.safetensors` (absent in older runs:
    /// with sky).
    #[serde(skip_serializing_if = "is_with_sky")]
    pub select_by: Selection,
    /// The weights the run trains (absent in older runs: all of them).
    #[serde(skip_serializing_if = "is_all")]
    pub train_only: TrainParts,
}

fn one_thread() -> usize {
    1
}

fn is_one_thread(threads: &usize) -> bool {
    *threads == 1
}

fn is_all(parts: &TrainParts) -> bool {
    *parts == TrainParts::All
}

fn is_with_sky(selection: &Selection) -> bool {
    *selection == Selection::WithSky
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            net: NetConfig::tiny(),
            data: Vec::new(),
            train_frames: None,
            val_frames: None,
            val_fraction: 0.1,
            epochs: 30,
            lr: 0.003,
            lr_low: 0.0003,
            low_lr_epochs: None,
            optimizer: Optimizer::Sgd,
            momentum: 0.9,
            weight_decay: 0.0,
            seed: 0,
            rotations: 8,
            max_rotation_deg: 5.0,
            permute_cameras: true,
            max_steps_per_epoch: None,
            max_val_frames: None,
            prefetch: 4,
            loader_threads: 1,
            init: None,
            column_window: None,
            photometric: None,
            frozen_norm_stats: false,
            select_by: Selection::WithSky,
            train_only: TrainParts::All,
        }
    }
}

impl TrainConfig {
    /// The learning rate of `epoch` (0-based): `lr`, then `lr_low` for the last
    /// `low_lr_epochs` (a third of the epochs unless given).
    pub fn lr_at(&self, epoch: usize) -> f64 {
        let low = self.low_lr_epochs.unwrap_or(self.epochs / 3);
        if epoch + low >= self.epochs && low > 0 {
            self.lr_low
        } else {
            self.lr
        }
    }

    /// Checks the values a run needs.
    ///
    /// # Errors
    /// [`TrainError::InvalidConfig`] naming the field.
    pub fn validate(&self) -> Result<(), TrainError> {
        let invalid =
            |field: &'static str, message: String| TrainError::InvalidConfig { field, message };
        self.net.validate()?;
        if self.epochs == 0 {
            return Err(invalid("epochs", "must be at least 1".into()));
        }
        if !(self.lr > 0.0 && self.lr_low > 0.0) {
            return Err(invalid(
                "lr",
                format!("must be positive, got {} and {}", self.lr, self.lr_low),
            ));
        }
        if !(0.0..1.0).contains(&self.momentum) {
            return Err(invalid(
                "momentum",
                format!("must be in [0, 1), got {}", self.momentum),
            ));
        }
        if self.loader_threads == 0 || self.loader_threads > 64 {
            return Err(invalid(
                "loader_threads",
                format!("must be 1 to 64, got {}", self.loader_threads),
            ));
        }
        if self.rotations == 0 {
            return Err(invalid(
                "rotations",
                "must be at least 1 (the identity)".into(),
            ));
        }
        if !(0.0..=1.0).contains(&self.val_fraction) {
            return Err(invalid(
                "val_fraction",
                format!("must be in [0, 1], got {}", self.val_fraction),
            ));
        }
        if let Some(w) = self.column_window {
            if self.net.family != Family::Cascade {
                return Err(invalid(
                    "column_window",
                    "only the cascade network trains on a window of longitudes".into(),
                ));
            }
            if w < 2 || !w.is_multiple_of(2) || w > self.net.out_width {
                return Err(invalid(
                    "column_window",
                    format!(
                        "{w} must be even, at least 2 and at most the output's {} columns",
                        self.net.out_width
                    ),
                ));
            }
        }
        if let Some(p) = &self.photometric {
            p.validate()?;
        }
        for (field, range) in [
            ("train_frames", self.train_frames),
            ("val_frames", self.val_frames),
        ] {
            if let Some((a, b)) = range
                && b < a
            {
                return Err(invalid(field, format!("{a}..{b} is reversed")));
            }
        }
        Ok(())
    }

    /// Splits the frames found in one dataset into training and validation frames.
    pub fn split(&self, found: &[u32]) -> (Vec<u32>, Vec<u32>) {
        let inside = |r: Option<(u32, u32)>, f: u32| r.is_some_and(|(a, b)| (a..=b).contains(&f));
        let val: Vec<u32> = match self.val_frames {
            Some(_) => found
                .iter()
                .copied()
                .filter(|&f| inside(self.val_frames, f))
                .collect(),
            None => {
                let count = ((found.len() as f64 * self.val_fraction).round() as usize)
                    .clamp(usize::from(found.len() > 1), found.len().saturating_sub(1));
                found[found.len() - count..].to_vec()
            }
        };
        let train = found
            .iter()
            .copied()
            .filter(|f| !val.contains(f))
            .filter(|&f| self.train_frames.is_none() || inside(self.train_frames, f))
            .collect();
        (train, val)
    }
}

/// `A..B` of an inclusive range, as written in the configuration.
pub fn range_pair(range: &RangeInclusive<u32>) -> (u32, u32) {
    (*range.start(), *range.end())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_drops_for_the_last_third() {
        let config = TrainConfig {
            epochs: 30,
            ..TrainConfig::default()
        };
        assert_eq!(config.lr_at(0), 0.003);
        assert_eq!(config.lr_at(19), 0.003);
        assert_eq!(config.lr_at(20), 0.0003);
        assert_eq!(config.lr_at(29), 0.0003);
        let ft = TrainConfig {
            epochs: 16,
            low_lr_epochs: Some(4),
            ..TrainConfig::default()
        };
        assert_eq!(ft.lr_at(11), 0.003);
        assert_eq!(ft.lr_at(12), 0.0003);
        let one = TrainConfig {
            epochs: 1,
            ..TrainConfig::default()
        };
        assert_eq!(one.lr_at(0), 0.003);
    }

    #[test]
    fn splits_by_frame_index() {
        let found: Vec<u32> = (1..=20).collect();
        let config = TrainConfig::default();
        let (train, val) = config.split(&found);
        assert_eq!(val, vec![19, 20]);
        assert_eq!(train, (1..=18).collect::<Vec<_>>());
        let config = TrainConfig {
            train_frames: Some((1, 5)),
            val_frames: Some((10, 12)),
            ..TrainConfig::default()
        };
        let (train, val) = config.split(&found);
        assert_eq!(train, vec![1, 2, 3, 4, 5]);
        assert_eq!(val, vec![10, 11, 12]);
        let json = serde_json::to_string(&config).unwrap();
        assert_eq!(serde_json::from_str::<TrainConfig>(&json).unwrap(), config);
        assert!(
            TrainConfig {
                epochs: 0,
                ..config
            }
            .validate()
            .is_err()
        );
    }
}
