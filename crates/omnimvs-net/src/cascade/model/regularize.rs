//! The convolution blocks that score a stage's cost volume: the coarse stage's 2D
//! encoder-decoder and the refinement stages' scoring convolutions, both of panorama
//! convolutions that wrap in longitude ([`ConvBn2d::pano`]).

use burn::module::Module;
use burn::nn::conv::{Conv2d, ConvTranspose2d, ConvTranspose2dConfig};
use burn::nn::{BatchNorm, BatchNormConfig};
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Tensor};

use crate::model::blocks::ConvBn2d;

/// Stride-2 transposed 3x3 convolution (doubles rows and columns), batch norm, the skip
/// addition, ReLU.
#[derive(Module, Debug)]
pub struct Up2d {
    /// The transposed convolution.
    pub conv: ConvTranspose2d,
    /// Batch norm.
    pub bn: BatchNorm,
}

impl Up2d {
    pub(super) fn new(channels: [usize; 2], device: &Device) -> Self {
        Self {
            conv: ConvTranspose2dConfig::new(channels, [3, 3])
                .with_stride([2, 2])
                .with_padding([1, 1])
                .with_padding_out([1, 1])
                .init(device),
            bn: BatchNormConfig::new(channels[1]).init(device),
        }
    }

    /// `[B, C_in, H, W]` and a skip `[B, C_out, 2H, 2W]` -> `[B, C_out, 2H, 2W]`.
    pub fn forward(&self, x: Tensor<4>, skip: Tensor<4>) -> Tensor<4> {
        let x = self.bn.forward(self.conv.forward(x)); // [B, C_out, 2H, 2W]
        relu(x + skip)
    }
}

/// The coarse stage's 2D encoder-decoder over the cost volume (channels = groups x spheres):
/// two stride-2 levels, skip additions, one score per sphere.
#[derive(Module, Debug)]
pub struct CoarseRegularizer {
    /// Full-resolution convolutions.
    pub c0: Vec<ConvBn2d>,
    /// Half resolution.
    pub c1: Vec<ConvBn2d>,
    /// Quarter resolution.
    pub c2: Vec<ConvBn2d>,
    /// Quarter -> half.
    pub up1: Up2d,
    /// Half -> full.
    pub up0: Up2d,
    /// Final score per sphere.
    pub out: ConvBn2d,
}

fn fold_pano(blocks: Vec<ConvBn2d>) -> Vec<ConvBn2d> {
    blocks.into_iter().map(ConvBn2d::fold_batch_norm).collect()
}

fn host_pano(blocks: Vec<ConvBn2d>) -> Vec<ConvBn2d> {
    blocks.into_iter().map(ConvBn2d::with_host_conv).collect()
}

fn run(blocks: &[ConvBn2d], x: Tensor<4>) -> Tensor<4> {
    blocks.iter().fold(x, |x, b| b.forward(x, None))
}

impl CoarseRegularizer {
    pub(super) fn new(cin: usize, spheres: usize, [a, b, c]: [usize; 3], device: &Device) -> Self {
        let conv = |i, o, s| ConvBn2d::pano([i, o], s, true, device);
        Self {
            c0: vec![conv(cin, a, 1), conv(a, a, 1)],
            c1: vec![conv(a, b, 2), conv(b, b, 1)],
            c2: vec![conv(b, c, 2), conv(c, c, 1)],
            up1: Up2d::new([c, b], device),
            up0: Up2d::new([b, a], device),
            out: ConvBn2d::pano([a, spheres], 1, false, device),
        }
    }

    /// Folds the batch norms of its convolutions (those of the transposed convolutions stay:
    /// they run at the two coarsest levels).
    #[must_use]
    pub fn fold_batch_norm(self) -> Self {
        Self {
            c0: fold_pano(self.c0),
            c1: fold_pano(self.c1),
            c2: fold_pano(self.c2),
            up1: self.up1,
            up0: self.up0,
            out: self.out.fold_batch_norm(),
        }
    }

    /// Its 3x3 convolutions also on the host ([`ConvBn2d::with_host_conv`]).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            c0: host_pano(self.c0),
            c1: host_pano(self.c1),
            c2: host_pano(self.c2),
            out: self.out.with_host_conv(),
            ..self
        }
    }

    /// `[B, C, H, W]` -> scores `[B, D, H, W]`.
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let x0 = run(&self.c0, x); // [B, a, H, W]
        let x1 = run(&self.c1, x0.clone()); // [B, b, H/2, W/2]
        let x2 = run(&self.c2, x1.clone()); // [B, c, H/4, W/4]
        let y1 = self.up1.forward(x2, x1); // [B, b, H/2, W/2]
        let y0 = self.up0.forward(y1, x0); // [B, a, H, W]
        self.out.forward(y0, None) // [B, D, H, W]
    }

    /// The convolution that reads the evidence channels, the first 3x3 convolution. Growing
    /// or resampling the evidence changes its inputs.
    pub(super) fn input_conv(&mut self) -> &mut Conv2d {
        &mut self.c0[0].conv
    }
}

/// A refinement stage's 2D convolutions over its per-pixel hypotheses.
#[derive(Module, Debug)]
pub struct StageRegularizer {
    /// Two 3x3 convolutions with batch norm and ReLU.
    pub convs: Vec<ConvBn2d>,
    /// Final score per hypothesis.
    pub out: ConvBn2d,
    /// The gate between the stage's answer and its centre (logit), when the stage has one.
    pub gate: Option<ConvBn2d>,
}

/// The gate's starting logit: `sigmoid(4) = 0.98`, the stage's own answer almost unchanged.
const GATE_START_LOGIT: f32 = 4.0;

impl StageRegularizer {
    pub(super) fn new(cin: usize, ch: usize, k: usize, gate: bool, device: &Device) -> Self {
        Self {
            convs: vec![
                ConvBn2d::pano([cin, ch], 1, true, device),
                ConvBn2d::pano([ch, ch], 1, true, device),
            ],
            out: ConvBn2d::pano([ch, k], 1, false, device),
            gate: gate.then(|| ConvBn2d::pano_constant([ch, 1], GATE_START_LOGIT, device)),
        }
    }

    /// Its convolutions also on the host ([`ConvBn2d::with_host_conv`]).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            convs: host_pano(self.convs),
            out: self.out.with_host_conv(),
            gate: self.gate.map(ConvBn2d::with_host_conv),
        }
    }

    /// Folds the batch norms into the convolutions.
    #[must_use]
    pub fn fold_batch_norm(self) -> Self {
        Self {
            convs: fold_pano(self.convs),
            out: self.out.fold_batch_norm(),
            gate: self.gate.map(ConvBn2d::fold_batch_norm),
        }
    }

    /// `[B, C, H, W]` -> scores `[B, K, H, W]` and, with a gate, its value `[B, H, W]`.
    pub fn forward(&self, x: Tensor<4>) -> (Tensor<4>, Option<Tensor<3>>) {
        let hidden = run(&self.convs, x); // [B, ch, H, W]
        let gate = self
            .gate
            .as_ref()
            .map(|g| sigmoid(g.forward(hidden.clone(), None)).squeeze_dim(1)); // [B, H, W]
        (self.out.forward(hidden, None), gate) // [B, K, H, W]
    }
}
