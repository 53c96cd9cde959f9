//! The convolution blocks that score a stage's cost volume: the panorama convolution that
//! wraps in longitude, the coarse stage's 2D encoder-decoder and the refinement stages'
//! scoring convolutions.

use std::sync::Arc;

use burn::module::Module;
use burn::module::Param;
use burn::nn::Initializer;
use burn::nn::conv::{Conv2d, Conv2dConfig, ConvTranspose2d, ConvTranspose2dConfig};
use burn::nn::{BatchNorm, BatchNormConfig, PaddingConfig2d};
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Tensor};

use crate::hostconv::{HostConv, host_forward};
use crate::model::blocks::fold_into_conv2d;

/// 3x3 convolution on the panorama grid that wraps around in longitude (the columns are a
/// circle) and is zero-padded in latitude; optional batch norm and ReLU. The cost
/// regularisation works on 2D maps whose channels are (groups x hypotheses): on a CPU a 2D
/// convolution with many channels runs near the GEMM peak, where a 3D convolution with a
/// handful of channels over the same volume is memory-bound (measured 10x slower per FLOP
/// with burn's flex backend, see the README).
#[derive(Module, Debug)]
pub struct PanoConv2d {
    /// The convolution (no padding along columns: the input is padded circularly).
    pub conv: Conv2d,
    /// Batch norm.
    pub bn: Option<BatchNorm>,
    /// Whether a ReLU ends the block.
    #[module(skip)]
    pub relu: bool,
    /// The same convolution on the host, with the longitude wrap in its addressing
    /// ([`PanoConv2d::with_host_conv`]: inference on a CPU).
    #[module(skip)]
    pub host: Option<Arc<HostConv>>,
}

impl PanoConv2d {
    /// A `channels[0] -> channels[1]` block with random weights and a bias, at `stride`; with
    /// `bn_relu`, a batch norm and a ReLU after the convolution.
    pub fn new(channels: [usize; 2], stride: usize, bn_relu: bool, device: &Device) -> Self {
        let conv = Conv2dConfig::new(channels, [3, 3])
            .with_stride([stride, stride])
            .with_padding(PaddingConfig2d::Explicit(1, 0, 1, 0))
            .init(device);
        Self {
            conv,
            bn: bn_relu.then(|| BatchNormConfig::new(channels[1]).init(device)),
            relu: bn_relu,
            host: None,
        }
    }

    /// A convolution whose output starts at `bias` everywhere (zero weights), no batch norm.
    pub(super) fn constant(channels: [usize; 2], bias: f32, device: &Device) -> Self {
        let mut conv = Conv2dConfig::new(channels, [3, 3])
            .with_padding(PaddingConfig2d::Explicit(1, 0, 1, 0))
            .with_initializer(Initializer::Zeros)
            .init(device);
        conv.bias = Some(Param::from_tensor(Tensor::full(
            [channels[1]],
            bias,
            device,
        )));
        Self {
            conv,
            bn: None,
            relu: false,
            host: None,
        }
    }

    /// Folds an inference-mode batch norm into the convolution.
    #[must_use]
    pub fn fold_batch_norm(mut self) -> Self {
        fold_into_conv2d(&mut self.conv, self.bn.take());
        self
    }

    /// The block with its convolution also on the host ([`HostConv`]), used by
    /// [`PanoConv2d::forward`] from then on: for inference on a CPU, after
    /// [`PanoConv2d::fold_batch_norm`] (a block that still has its batch norm is returned as
    /// it is).
    #[must_use]
    pub fn with_host_conv(mut self) -> Self {
        if self.bn.is_none() {
            self.host = HostConv::from_conv(&self.conv, 1, true).map(Arc::new);
        }
        self
    }

    /// `[B, C_in, H, W] -> [B, C_out, H', W']`.
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let x = match &self.host {
            Some(host) => match host_forward(host, x, None, self.relu) {
                Ok(y) => return y,
                Err(declined) => declined.0,
            },
            None => x,
        };
        let [_, _, _, w] = x.dims();
        let first = x.clone().narrow(3, 0, 1);
        let last = x.clone().narrow(3, w - 1, 1);
        let x = Tensor::cat(vec![last, x, first], 3); // [B, C, H, W + 2]
        let x = self.conv.forward(x); // [B, C_out, H', W']
        bn_relu(x, self.bn.as_ref(), self.relu)
    }
}

fn bn_relu(x: Tensor<4>, bn: Option<&BatchNorm>, relu_after: bool) -> Tensor<4> {
    let x = match bn {
        Some(bn) => bn.forward(x),
        None => x,
    };
    if relu_after { relu(x) } else { x }
}

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
    /// The 1x1 convolution (no bias) the evidence passes through first (`coarse_squeeze`),
    /// when the network has one.
    pub squeeze: Option<Conv2d>,
    /// Full-resolution convolutions.
    pub c0: Vec<PanoConv2d>,
    /// Half resolution.
    pub c1: Vec<PanoConv2d>,
    /// Quarter resolution.
    pub c2: Vec<PanoConv2d>,
    /// Quarter -> half.
    pub up1: Up2d,
    /// Half -> full.
    pub up0: Up2d,
    /// Final score per sphere.
    pub out: PanoConv2d,
}

fn fold_pano(blocks: Vec<PanoConv2d>) -> Vec<PanoConv2d> {
    blocks
        .into_iter()
        .map(PanoConv2d::fold_batch_norm)
        .collect()
}

fn host_pano(blocks: Vec<PanoConv2d>) -> Vec<PanoConv2d> {
    blocks.into_iter().map(PanoConv2d::with_host_conv).collect()
}

fn run(blocks: &[PanoConv2d], x: Tensor<4>) -> Tensor<4> {
    blocks.iter().fold(x, |x, b| b.forward(x))
}

impl CoarseRegularizer {
    /// `squeeze` 0: none ([`CoarseRegularizer::squeeze`]).
    pub(super) fn new(
        cin: usize,
        squeeze: usize,
        spheres: usize,
        [a, b, c]: [usize; 3],
        device: &Device,
    ) -> Self {
        let conv = |i, o, s| PanoConv2d::new([i, o], s, true, device);
        let first = if squeeze > 0 { squeeze } else { cin };
        Self {
            squeeze: (squeeze > 0).then(|| squeeze_conv(cin, squeeze, device)),
            c0: vec![conv(first, a, 1), conv(a, a, 1)],
            c1: vec![conv(a, b, 2), conv(b, b, 1)],
            c2: vec![conv(b, c, 2), conv(c, c, 1)],
            up1: Up2d::new([c, b], device),
            up0: Up2d::new([b, a], device),
            out: PanoConv2d::new([a, spheres], 1, false, device),
        }
    }

    /// Folds the batch norms of its convolutions (those of the transposed convolutions stay:
    /// they run at the two coarsest levels).
    #[must_use]
    pub fn fold_batch_norm(self) -> Self {
        Self {
            squeeze: self.squeeze,
            c0: fold_pano(self.c0),
            c1: fold_pano(self.c1),
            c2: fold_pano(self.c2),
            up1: self.up1,
            up0: self.up0,
            out: self.out.fold_batch_norm(),
        }
    }

    /// Its 3x3 convolutions also on the host ([`PanoConv2d::with_host_conv`]).
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
        let x = match &self.squeeze {
            Some(squeeze) => squeeze.forward(x), // [B, squeeze, H, W]
            None => x,
        };
        let x0 = run(&self.c0, x); // [B, a, H, W]
        let x1 = run(&self.c1, x0.clone()); // [B, b, H/2, W/2]
        let x2 = run(&self.c2, x1.clone()); // [B, c, H/4, W/4]
        let y1 = self.up1.forward(x2, x1); // [B, b, H/2, W/2]
        let y0 = self.up0.forward(y1, x0); // [B, a, H, W]
        self.out.forward(y0) // [B, D, H, W]
    }

    /// The convolution that reads the evidence channels: the squeeze when there is one, else
    /// the first 3x3 convolution. Growing or resampling the evidence changes its inputs.
    pub(super) fn input_conv(&mut self) -> &mut Conv2d {
        match &mut self.squeeze {
            Some(squeeze) => squeeze,
            None => &mut self.c0[0].conv,
        }
    }
}

/// A 1x1 convolution from `cin` to `cout` channels without bias ([`CoarseRegularizer::squeeze`]).
pub(super) fn squeeze_conv(cin: usize, cout: usize, device: &Device) -> Conv2d {
    Conv2dConfig::new([cin, cout], [1, 1])
        .with_padding(PaddingConfig2d::Valid)
        .with_bias(false)
        .init(device)
}

/// A refinement stage's 2D convolutions over its per-pixel hypotheses.
#[derive(Module, Debug)]
pub struct StageRegularizer {
    /// Two 3x3 convolutions with batch norm and ReLU.
    pub convs: Vec<PanoConv2d>,
    /// Final score per hypothesis.
    pub out: PanoConv2d,
    /// The gate between the stage's answer and its centre (logit), when the stage has one.
    pub gate: Option<PanoConv2d>,
}

/// The gate's starting logit: `sigmoid(4) = 0.98`, the stage's own answer almost unchanged.
const GATE_START_LOGIT: f32 = 4.0;

impl StageRegularizer {
    pub(super) fn new(cin: usize, ch: usize, k: usize, gate: bool, device: &Device) -> Self {
        Self {
            convs: vec![
                PanoConv2d::new([cin, ch], 1, true, device),
                PanoConv2d::new([ch, ch], 1, true, device),
            ],
            out: PanoConv2d::new([ch, k], 1, false, device),
            gate: gate.then(|| PanoConv2d::constant([ch, 1], GATE_START_LOGIT, device)),
        }
    }

    /// Its convolutions also on the host ([`PanoConv2d::with_host_conv`]).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            convs: host_pano(self.convs),
            out: self.out.with_host_conv(),
            gate: self.gate.map(PanoConv2d::with_host_conv),
        }
    }

    /// Folds the batch norms into the convolutions.
    #[must_use]
    pub fn fold_batch_norm(self) -> Self {
        Self {
            convs: fold_pano(self.convs),
            out: self.out.fold_batch_norm(),
            gate: self.gate.map(PanoConv2d::fold_batch_norm),
        }
    }

    /// `[B, C, H, W]` -> scores `[B, K, H, W]` and, with a gate, its value `[B, H, W]`.
    pub fn forward(&self, x: Tensor<4>) -> (Tensor<4>, Option<Tensor<3>>) {
        let hidden = run(&self.convs, x); // [B, ch, H, W]
        let gate = self
            .gate
            .as_ref()
            .map(|g| sigmoid(g.forward(hidden.clone())).squeeze_dim(1)); // [B, H, W]
        (self.out.forward(hidden), gate) // [B, K, H, W]
    }
}
