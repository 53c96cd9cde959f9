//! The coarse-to-fine network: features at three strides, a group-wise correlation cost
//! volume over a few spheres at a quarter of the output resolution regularised by a small 2D encoder-decoder (hypotheses as channels), then two
//! stages of per-pixel hypotheses around the previous estimate.
//!
//! This file holds the network ([`CascadeNet`]: building, batch-norm folding, host
//! convolutions) and a stage's result ([`StageOutput`]); the rest by stage:
//!
//! - [`features`]: the feature pyramid at strides 2, 4 and 8.
//! - [`regularize`]: the convolution blocks that score a stage's cost volume.
//! - [`upsample`]: the learnt upsampling of an answer to the next grid.
//! - [`stages`]: the stages' forward computations (correlation, scores, soft argmax).
//! - [`grow`]: the `with_*` growth of a trained network into a new option.

pub mod features;
pub mod grow;
pub mod regularize;
pub mod stages;
pub mod upsample;

pub use features::CascadeFeatures;
pub use grow::{GROWABLE, GrowRule, GrowWeights, Growable, sphere_resampling};
pub use regularize::{CoarseRegularizer, StageRegularizer, Up2d};
pub use upsample::{
    CandidateSelector, UPSAMPLE_TAPS, bilinear_prior, convex_combination, upsampling_candidates,
};

use burn::module::Module;
use burn::tensor::{Device, Tensor};

use crate::config::{Family, NetConfig};
use crate::error::NetError;
use crate::model::softargmin::entropy;

/// One stage's result.
#[derive(Clone, Debug)]
pub struct StageOutput {
    /// Per-pixel distribution over the stage's hypotheses `[B, K, H, W]`.
    pub prob: Tensor<4>,
    /// Expected hypothesis index in `N` units `[B, H, W]`.
    pub index: Tensor<3>,
    /// The hypotheses the distribution is over, `N` units `[1, K, H, W]` (no gradient).
    pub hypotheses: Tensor<4>,
}

impl StageOutput {
    /// Entropy of the per-pixel distribution `[B, H, W]` (nats).
    pub fn entropy(&self) -> Tensor<3> {
        entropy(self.prob.clone())
    }
}

/// The cascade network. Build it with [`CascadeNet::new`] from a [`Family::Cascade`]
/// configuration; run it with [`CascadeNet::forward`] over a
/// [`super::CascadeGeometry`].
#[derive(Module, Debug)]
pub struct CascadeNet {
    /// Feature pyramid shared by every camera.
    pub features: CascadeFeatures,
    /// Coarse cost volume regularisation.
    pub coarse: CoarseRegularizer,
    /// Half-resolution refinement.
    pub mid: StageRegularizer,
    /// Full-resolution refinement.
    pub fine: StageRegularizer,
    /// Learnt upsampling of the coarse answer to the half-resolution grid
    /// (`convex_upsampling`), from the matching evidence of the stride-4 features.
    pub up_mid: Option<CandidateSelector>,
    /// Learnt upsampling of the half-resolution answer to the output grid, from that of the
    /// stride-2 features (`convex_upsampling` and `convex_upsampling_full`).
    pub up_fine: Option<CandidateSelector>,
    /// The sizes the network was built for.
    #[module(skip)]
    pub config: NetConfig,
}

impl CascadeNet {
    /// Builds a randomly initialised network.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when `config` is not a valid cascade configuration.
    pub fn new(config: &NetConfig, device: &Device) -> Result<Self, NetError> {
        if config.family != Family::Cascade {
            return Err(NetError::InvalidConfig {
                field: "family",
                message: format!("expected `cascade`, got {:?}", config.family),
            });
        }
        config.validate()?;
        let p = &config.cascade;
        Ok(Self {
            features: CascadeFeatures::new(p.feature_channels, p.context_pairs, device),
            coarse: CoarseRegularizer::new(
                p.coarse_evidence_channels() * p.coarse_spheres,
                p.coarse_spheres,
                p.coarse_channels,
                device,
            ),
            mid: StageRegularizer::new(
                p.stage_evidence_channels(0) * p.stage_hypotheses[0],
                p.stage_channels[0],
                p.stage_hypotheses[0],
                p.stage_gates,
                device,
            ),
            fine: StageRegularizer::new(
                p.stage_evidence_channels(1) * p.stage_hypotheses[1],
                p.stage_channels[1],
                p.stage_hypotheses[1],
                p.stage_gates,
                device,
            ),
            up_mid: p
                .convex_upsampling
                .then(|| CandidateSelector::for_stage(p, 0, device)),
            up_fine: (p.convex_upsampling && p.convex_upsampling_full)
                .then(|| CandidateSelector::for_stage(p, 1, device)),
            config: config.clone(),
        })
    }

    /// The network for inference with its batch norms folded into the convolutions before
    /// them (the same answers, fewer passes over the feature maps); not for training.
    #[must_use]
    pub fn fold_batch_norm(self) -> Self {
        Self {
            features: self.features.fold_batch_norm(),
            coarse: self.coarse.fold_batch_norm(),
            mid: self.mid.fold_batch_norm(),
            fine: self.fine.fold_batch_norm(),
            up_mid: self.up_mid,
            up_fine: self.up_fine,
            config: self.config,
        }
    }

    /// The network with its convolutions also on the host ([`crate::hostconv`]), which its
    /// forward pass uses from then on: for inference on a CPU, after
    /// [`CascadeNet::fold_batch_norm`] (blocks that still have a batch norm keep burn's path).
    /// The same answers to float rounding; not for training.
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            features: self.features.with_host_convs(),
            coarse: self.coarse.with_host_convs(),
            mid: self.mid.with_host_convs(),
            fine: self.fine.with_host_convs(),
            up_mid: self.up_mid.map(CandidateSelector::with_host_convs),
            up_fine: self.up_fine.map(CandidateSelector::with_host_convs),
            config: self.config,
        }
    }
}
