//! The model and its optimiser: one SGD step on the loss of [`crate::loss`], and checkpoints
//! that restore both exactly (burnpack files keep the parameter ids the optimiser state is
//! keyed by).

use std::path::{Path, PathBuf};

use burn::module::{Flag, Module, ModuleMapper, Param};
use burn::optim::decay::WeightDecayConfig;
use burn::optim::momentum::MomentumConfig;
use burn::optim::{AdamConfig, GradientsParams, ModuleOptimizer, SgdConfig};
use burn::store::{BurnpackStore, ModuleSnapshot};
use burn::tensor::{Device, Tensor};
use omnimvs_core::fs::write_atomic;
use omnimvs_net::model::{OmniMvsNet, SweepTaps};

use crate::config::{Optimizer, TrainConfig, TrainParts};
use crate::error::TrainError;
use crate::sample::Sample;
use crate::trainable::Trainable;

/// File of the model inside a checkpoint folder.
pub const MODEL_FILE: &str = "model.bpk";
/// File of the optimiser state inside a checkpoint folder.
pub const OPTIM_FILE: &str = "optim.bpk";

fn ckpt_error(path: &Path, message: impl std::fmt::Display) -> TrainError {
    TrainError::Checkpoint {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// Turns every module-owned training flag off (in these networks: the batch norms', which then
/// normalise with their running statistics and leave them as they are, while their scale and
/// shift still take gradients).
struct NormStatsFrozen;

impl ModuleMapper for NormStatsFrozen {
    fn map_flag(&mut self, flag: Param<Flag>) -> Param<Flag> {
        Param::initialized(flag.id, Flag::new(false))
    }
}

/// `net` with its batch norms' statistics frozen when `frozen` (see
/// [`TrainConfig::frozen_norm_stats`]).
fn with_norm_stats<M: Module>(net: M, frozen: bool) -> M {
    if frozen {
        net.map(&mut NormStatsFrozen)
    } else {
        net
    }
}

/// The network being trained (on an autodiff device) and its optimiser.
pub struct Learner<M = OmniMvsNet> {
    /// The network.
    pub net: M,
    /// The optimiser and its momentum (or moment) buffers.
    pub optim: ModuleOptimizer,
    /// The autodiff device.
    pub device: Device,
    optimizer: Optimizer,
    optimizer_config: OptimizerSettings,
    train_only: TrainParts,
}

/// The settings [`Learner::load_checkpoint`] needs to rebuild the optimiser.
#[derive(Clone, Copy, Debug)]
struct OptimizerSettings {
    momentum: f64,
    weight_decay: f64,
}

fn init_optimizer(kind: Optimizer, s: OptimizerSettings) -> ModuleOptimizer {
    let decay = (s.weight_decay > 0.0).then_some(WeightDecayConfig {
        penalty: s.weight_decay as f32,
    });
    match kind {
        Optimizer::Sgd => {
            let mut sgd = SgdConfig::new().with_momentum(Some(MomentumConfig {
                momentum: s.momentum,
                dampening: 0.0,
                nesterov: false,
            }));
            if let Some(decay) = decay {
                sgd = sgd.with_weight_decay(Some(decay));
            }
            sgd.init()
        }
        Optimizer::Adam => AdamConfig::new()
            .with_beta_1(s.momentum as f32)
            .with_weight_decay(decay)
            .init(),
    }
}

impl Learner {
    /// A learner of the paper's network for `config` on `device` (autodiff is added): the
    /// network starts from `config.init` when given, else from random weights seeded with
    /// `config.seed`.
    ///
    /// # Errors
    /// [`TrainError`] for an invalid configuration or unreadable initial weights.
    pub fn new(config: &TrainConfig, device: &Device) -> Result<Self, TrainError> {
        Self::for_model(config, device)
    }

    /// Sweep taps of one camera set on the training device.
    pub fn taps(&self, grids: &[omnimvs_net::taps::SweepGrid]) -> Vec<SweepTaps> {
        SweepTaps::for_grids(grids, self.net.config.feature_size(), &self.device)
    }
}

impl<M: Trainable> Learner<M> {
    /// A learner of any [`Trainable`] family for `config` on `device` (autodiff is added).
    ///
    /// # Errors
    /// [`TrainError`] for an invalid configuration or unreadable initial weights.
    pub fn for_model(config: &TrainConfig, device: &Device) -> Result<Self, TrainError> {
        config.validate()?;
        let device = device.clone().autodiff();
        device.seed(config.seed);
        // Training only some weights keeps the others' batch-norm statistics too.
        let net = with_norm_stats(
            M::build(&config.net, config.init.as_deref(), &device)?,
            config.frozen_norm_stats || config.train_only != TrainParts::All,
        )
        .train_only(config.train_only)?;
        let built = net.config();
        if built.out_height != config.net.out_height
            || built.out_width != config.net.out_width
            || built.num_invdepth != config.net.num_invdepth
        {
            return Err(TrainError::InvalidConfig {
                field: "init",
                message: format!(
                    "the weights' output {}x{} N={} differs from the run's {}x{} N={}",
                    built.out_height,
                    built.out_width,
                    built.num_invdepth,
                    config.net.out_height,
                    config.net.out_width,
                    config.net.num_invdepth
                ),
            });
        }
        let settings = OptimizerSettings {
            momentum: config.momentum,
            weight_decay: config.weight_decay,
        };
        Ok(Self {
            net,
            optim: init_optimizer(config.optimizer, settings),
            device,
            optimizer: config.optimizer,
            train_only: config.train_only,
            optimizer_config: settings,
        })
    }

    /// The sample's images as `[1, 1, H_I, W_I]` tensors on `device`.
    pub fn image_tensors_on(&self, sample: &Sample, device: &Device) -> Vec<Tensor<4>> {
        let c = self.net.config();
        sample.image_tensors([c.input_height, c.input_width], device)
    }

    /// The sample's images on the training device.
    pub fn image_tensors(&self, sample: &Sample) -> Vec<Tensor<4>> {
        self.image_tensors_on(sample, &self.device)
    }

    /// Loss of `sample` with the current weights, without updating them.
    ///
    /// # Errors
    /// [`TrainError`] for inputs that do not fit the network.
    pub fn loss(
        &self,
        sample: &Sample,
        geometry: &M::Geometry,
        order: &[usize],
    ) -> Result<Tensor<1>, TrainError> {
        let images = self.image_tensors(sample);
        self.net
            .loss(&images, geometry, order, sample, self.train_only)
    }

    /// One optimiser step on `sample` at learning rate `lr`; returns the loss before the
    /// step.
    ///
    /// # Errors
    /// [`TrainError`] for inputs that do not fit the network.
    pub fn step(
        &mut self,
        sample: &Sample,
        geometry: &M::Geometry,
        order: &[usize],
        lr: f64,
    ) -> Result<f32, TrainError> {
        let loss = self.loss(sample, geometry, order)?;
        let value = loss.clone().into_scalar::<f32>();
        let grads = GradientsParams::from_grads(loss.backward(), &self.net);
        self.net = self.optim.step(lr, self.net.clone(), grads);
        Ok(value)
    }

    /// The model and the optimiser state as burnpack files in memory (the bytes of
    /// [`MODEL_FILE`] and [`OPTIM_FILE`]: the same containers burn writes to a file).
    ///
    /// # Errors
    /// [`TrainError::Checkpoint`] (naming the file under `dir`) when burn cannot serialise them.
    pub fn checkpoint_bytes(&self, dir: &Path) -> Result<(Vec<u8>, Vec<u8>), TrainError> {
        let model = dir.join(MODEL_FILE);
        let mut store = BurnpackStore::from_bytes(None);
        self.net
            .save_into(&mut store)
            .map_err(|e| ckpt_error(&model, e))?;
        let model_bytes = store.get_bytes().map_err(|e| ckpt_error(&model, e))?;
        let optim = dir.join(OPTIM_FILE);
        let optim_bytes = self.optim.into_bytes().map_err(|e| ckpt_error(&optim, e))?;
        Ok((model_bytes.to_vec(), optim_bytes.to_vec()))
    }

    /// Writes the model and the optimiser state into `dir` (created if needed): both are
    /// serialised in memory first, then each file is written atomically, so a failure leaves
    /// any file of an earlier checkpoint there whole.
    ///
    /// # Errors
    /// [`TrainError`] when a file cannot be serialised or written.
    pub fn save_checkpoint(&self, dir: &Path) -> Result<(), TrainError> {
        std::fs::create_dir_all(dir).map_err(|source| TrainError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let (model_bytes, optim_bytes) = self.checkpoint_bytes(dir)?;
        for (name, bytes) in [(MODEL_FILE, model_bytes), (OPTIM_FILE, optim_bytes)] {
            let path = dir.join(name);
            write_atomic(&path, &bytes).map_err(|source| TrainError::Io { path, source })?;
        }
        Ok(())
    }

    /// Restores the model and the optimiser state written by [`Learner::save_checkpoint`]
    /// (tensors only: the batch norms' training flags, frozen or not, stay as the learner was
    /// built).
    ///
    /// # Errors
    /// [`TrainError`] when a file is missing or does not fit the network.
    pub fn load_checkpoint(&mut self, dir: &Path) -> Result<(), TrainError> {
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
        // Loaded parameters may come back trainable: freeze again what the run keeps.
        self.net = self.net.clone().train_only(self.train_only)?;
        let optim = dir.join(OPTIM_FILE);
        self.optim = init_optimizer(self.optimizer, self.optimizer_config)
            .load(&optim)
            .map_err(|e| ckpt_error(&optim, e))?;
        Ok(())
    }

    /// The network without autodiff and in inference mode (batch norms use running
    /// statistics), for validation.
    pub fn inference_net(&self) -> M {
        self.net.valid()
    }
}
