//! The model and its optimiser: the paper's masked L1 loss, one SGD step, and checkpoints
//! that restore both exactly (burnpack files keep the parameter ids the optimiser state is
//! keyed by).

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::optim::decay::WeightDecayConfig;
use burn::optim::momentum::MomentumConfig;
use burn::optim::{GradientsParams, ModuleOptimizer, SgdConfig};
use burn::store::{BurnpackStore, ModuleSnapshot};
use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_data::gt::GroundTruth;

use super::config::TrainConfig;
use super::sample::Sample;
use crate::error::NetError;
use crate::model::{OmniMvsNet, SweepTaps};
use crate::weights;

/// File of the model inside a checkpoint folder.
pub const MODEL_FILE: &str = "model.bpk";
/// File of the optimiser state inside a checkpoint folder.
pub const OPTIM_FILE: &str = "optim.bpk";

/// `mean over valid pixels of |index - target|`: `index`, `target` and `mask` (1 for valid
/// pixels, 0 elsewhere) are `[B, H, W]`; the target is the rounded ground-truth index.
pub fn masked_l1(index: Tensor<3>, target: Tensor<3>, mask: Tensor<3>) -> Tensor<1> {
    let count = mask.clone().sum().clamp_min(1.0); // [1]
    ((index - target).abs() * mask).sum() / count // [1]
}

/// Rounded ground-truth indices and the valid mask as `[1, H, W]` data.
pub fn target_data(gt: &GroundTruth) -> (TensorData, TensorData) {
    let shape = [1, gt.height, gt.width];
    let target: Vec<f32> = gt
        .index
        .iter()
        .zip(&gt.valid)
        .map(|(&n, &v)| if v { n.round() } else { 0.0 })
        .collect();
    let mask: Vec<f32> = gt.valid.iter().map(|&v| f32::from(u8::from(v))).collect();
    (TensorData::new(target, shape), TensorData::new(mask, shape))
}

fn ckpt_error(path: &Path, message: impl std::fmt::Display) -> NetError {
    NetError::Weights {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// The network being trained (on an autodiff device) and its SGD-with-momentum optimiser.
pub struct Learner {
    /// The network.
    pub net: OmniMvsNet,
    /// The optimiser and its momentum buffers.
    pub optim: ModuleOptimizer,
    /// The autodiff device.
    pub device: Device,
    sgd: SgdConfig,
}

impl Learner {
    /// A learner for `config` on `device` (autodiff is added): the network starts from
    /// `config.init` when given, else from random weights seeded with `config.seed`.
    ///
    /// # Errors
    /// [`NetError`] for an invalid configuration or unreadable initial weights.
    pub fn new(config: &TrainConfig, device: &Device) -> Result<Self, NetError> {
        config.validate()?;
        let device = device.clone().autodiff();
        device.seed(config.seed);
        let net = match &config.init {
            Some(path) => weights::load_any(path, &config.net, &device)?,
            None => OmniMvsNet::new(&config.net, &device)?,
        };
        if net.config.out_height != config.net.out_height
            || net.config.out_width != config.net.out_width
            || net.config.num_invdepth != config.net.num_invdepth
        {
            return Err(NetError::InvalidConfig {
                field: "init",
                message: format!(
                    "the weights' output {}x{} N={} differs from the run's {}x{} N={}",
                    net.config.out_height,
                    net.config.out_width,
                    net.config.num_invdepth,
                    config.net.out_height,
                    config.net.out_width,
                    config.net.num_invdepth
                ),
            });
        }
        let mut sgd = SgdConfig::new().with_momentum(Some(MomentumConfig {
            momentum: config.momentum,
            dampening: 0.0,
            nesterov: false,
        }));
        if config.weight_decay > 0.0 {
            sgd = sgd.with_weight_decay(Some(WeightDecayConfig {
                penalty: config.weight_decay as f32,
            }));
        }
        Ok(Self {
            net,
            optim: sgd.init(),
            device,
            sgd,
        })
    }

    /// The sample's images as `[1, 1, H_I, W_I]` tensors on the training device.
    pub fn image_tensors(&self, sample: &Sample) -> Vec<Tensor<4>> {
        let c = &self.net.config;
        sample
            .images
            .iter()
            .map(|image| {
                Tensor::from_data(
                    TensorData::new(image.clone(), [1, 1, c.input_height, c.input_width]),
                    &self.device,
                )
            })
            .collect()
    }

    /// Sweep taps of one camera set on the training device.
    pub fn taps(&self, grids: &[crate::taps::SweepGrid]) -> Vec<SweepTaps> {
        SweepTaps::for_grids(grids, self.net.config.feature_size(), &self.device)
    }

    /// Loss of `sample` with the current weights, without updating them.
    ///
    /// # Errors
    /// [`NetError`] for inputs that do not fit the network.
    pub fn loss(
        &self,
        sample: &Sample,
        taps: &[SweepTaps],
        order: &[usize],
    ) -> Result<Tensor<1>, NetError> {
        let images = self.image_tensors(sample);
        let out = self.net.forward(&images, taps, order)?; // index [1, H, W]
        let (target, mask) = target_data(&sample.gt);
        let target = Tensor::<3>::from_data(target, &self.device);
        let mask = Tensor::<3>::from_data(mask, &self.device);
        Ok(masked_l1(out.index, target, mask))
    }

    /// One SGD step on `sample` at learning rate `lr`; returns the loss before the step.
    ///
    /// # Errors
    /// [`NetError`] for inputs that do not fit the network.
    pub fn step(
        &mut self,
        sample: &Sample,
        taps: &[SweepTaps],
        order: &[usize],
        lr: f64,
    ) -> Result<f32, NetError> {
        let loss = self.loss(sample, taps, order)?;
        let value = loss.clone().into_scalar::<f32>();
        let grads = GradientsParams::from_grads(loss.backward(), &self.net);
        self.net = self.optim.step(lr, self.net.clone(), grads);
        Ok(value)
    }

    /// Writes the model and the optimiser state into `dir` (created if needed).
    ///
    /// # Errors
    /// [`NetError`] when a file cannot be written.
    pub fn save_checkpoint(&self, dir: &Path) -> Result<(), NetError> {
        std::fs::create_dir_all(dir).map_err(|source| NetError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let model = dir.join(MODEL_FILE);
        let mut store = BurnpackStore::from_file(&model)
            .auto_extension(false)
            .overwrite(true);
        self.net
            .save_into(&mut store)
            .map_err(|e| ckpt_error(&model, e))?;
        let optim = dir.join(OPTIM_FILE);
        self.optim.save(&optim).map_err(|e| ckpt_error(&optim, e))
    }

    /// Restores the model and the optimiser state written by [`Learner::save_checkpoint`].
    ///
    /// # Errors
    /// [`NetError`] when a file is missing or does not fit the network.
    pub fn load_checkpoint(&mut self, dir: &Path) -> Result<(), NetError> {
        let model: PathBuf = dir.join(MODEL_FILE);
        if !model.exists() {
            return Err(ckpt_error(&model, "no such checkpoint file"));
        }
        let mut store = BurnpackStore::from_file(&model).auto_extension(false);
        let result = self
            .net
            .load_from(&mut store)
            .map_err(|e| ckpt_error(&model, e))?;
        if !result.missing.is_empty() || !result.errors.is_empty() {
            return Err(ckpt_error(
                &model,
                format!(
                    "{} missing and {} unusable tensors",
                    result.missing.len(),
                    result.errors.len()
                ),
            ));
        }
        let optim = dir.join(OPTIM_FILE);
        self.optim = self
            .sgd
            .init()
            .load(&optim)
            .map_err(|e| ckpt_error(&optim, e))?;
        Ok(())
    }

    /// The network without autodiff and in inference mode (batch norms use running
    /// statistics), for validation.
    pub fn inference_net(&self) -> OmniMvsNet {
        self.net.valid()
    }
}
