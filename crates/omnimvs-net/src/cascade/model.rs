//! The coarse-to-fine network: features at three strides, a group-wise correlation cost
//! volume over a few spheres at a quarter (or, with `coarse_scale` 2, half) of the output
//! resolution regularised by a small 2D encoder-decoder (hypotheses as channels), then two
//! stages of per-pixel hypotheses around the previous estimate.

use std::sync::Arc;

use burn::module::Module;
use burn::module::Param;
use burn::nn::Initializer;
use burn::nn::conv::{Conv2d, Conv2dConfig, ConvTranspose2d, ConvTranspose2dConfig};
use burn::nn::{BatchNorm, BatchNormConfig, PaddingConfig2d};
use burn::tensor::activation::{relu, sigmoid, softmax};
use burn::tensor::{Device, Tensor, TensorData};

use super::geometry::StageTaps;
use crate::config::{CascadeParams, Family, NetConfig};
use crate::error::NetError;
use crate::hostconv::{HostConv, host_forward};
use crate::model::blocks::{ConvBn2d, fold_into_conv2d};
use crate::model::softargmin::entropy;
use crate::tensor::read_values;

/// Gray input images: one channel.
const INPUT_CHANNELS: usize = 1;

/// Feature pyramid shared by all cameras: strides 2, 4 and 8 of the input, each ending in a
/// linear 1x1 projection (signed features for the correlation).
#[derive(Module, Debug)]
pub struct CascadeFeatures {
    /// 5x5 stride-2 stem.
    pub conv0: ConvBn2d,
    /// 3x3 at stride 2.
    pub conv2: ConvBn2d,
    /// Projection of the stride-2 features.
    pub out2: ConvBn2d,
    /// 3x3 stride-2 down to stride 4.
    pub down4: ConvBn2d,
    /// Residual pair at stride 4.
    pub res4: Vec<ConvBn2d>,
    /// Projection of the stride-4 features.
    pub out4: ConvBn2d,
    /// 3x3 stride-2 down to stride 8.
    pub down8: ConvBn2d,
    /// Two residual pairs at stride 8, the second dilated by 2.
    pub res8: Vec<ConvBn2d>,
    /// Context residual pairs at stride 8 (dilated 4 and 8 in turn; none in the first
    /// cascades), each starting as the identity.
    pub ctx8: Vec<ConvBn2d>,
    /// Projection of the stride-8 features.
    pub out8: ConvBn2d,
}

impl CascadeFeatures {
    fn new(channels: [usize; 3], context_pairs: usize, device: &Device) -> Self {
        let [c2, c4, c8] = channels;
        let conv = |cin, cout, k, stride, pad, dil| {
            ConvBn2d::new([cin, cout], k, stride, pad, dil, true, true, device)
        };
        let project = |c| ConvBn2d::new([c, c], 1, 1, 0, 1, false, false, device);
        Self {
            conv0: conv(INPUT_CHANNELS, c2, 5, 2, 2, 1),
            conv2: conv(c2, c2, 3, 1, 1, 1),
            out2: project(c2),
            down4: conv(c2, c4, 3, 2, 1, 1),
            res4: vec![conv(c4, c4, 3, 1, 1, 1), conv(c4, c4, 3, 1, 1, 1)],
            out4: project(c4),
            down8: conv(c4, c8, 3, 2, 1, 1),
            res8: vec![
                conv(c8, c8, 3, 1, 1, 1),
                conv(c8, c8, 3, 1, 1, 1),
                conv(c8, c8, 3, 1, 2, 2),
                conv(c8, c8, 3, 1, 2, 2),
            ],
            ctx8: (0..context_pairs)
                .flat_map(|i| {
                    let dilation = if i % 2 == 0 { 4 } else { 8 };
                    let first = conv(c8, c8, 3, 1, dilation, dilation);
                    let second = conv(c8, c8, 3, 1, dilation, dilation).zero_residual();
                    [first, second]
                })
                .collect(),
            out8: project(c8),
        }
    }

    fn residual_pairs(blocks: &[ConvBn2d], mut x: Tensor<4>) -> Tensor<4> {
        for pair in blocks.chunks_exact(2) {
            let y = pair[0].forward(x.clone(), None);
            x = pair[1].forward(y, Some(x));
        }
        x
    }

    /// Every block of the pyramid passed through `f`.
    fn map_blocks(self, f: impl Fn(ConvBn2d) -> ConvBn2d) -> Self {
        let all = |blocks: Vec<ConvBn2d>| blocks.into_iter().map(&f).collect();
        Self {
            res4: all(self.res4),
            res8: all(self.res8),
            ctx8: all(self.ctx8),
            conv0: f(self.conv0),
            conv2: f(self.conv2),
            out2: f(self.out2),
            down4: f(self.down4),
            out4: f(self.out4),
            down8: f(self.down8),
            out8: f(self.out8),
        }
    }

    /// Folds the inference-mode batch norms into the convolutions.
    #[must_use]
    pub fn fold_batch_norm(self) -> Self {
        self.map_blocks(ConvBn2d::fold_batch_norm)
    }

    /// The features with every convolution also on the host ([`ConvBn2d::with_host_conv`]).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        self.map_blocks(ConvBn2d::with_host_conv)
    }

    /// The features with the stride-8 branch widened to `c8` channels (`down8`, the residual
    /// and context pairs, `out8`), answering as before but for a perturbation of about
    /// `NEW_PROJECTION_SCALE^2` of the coarse correlation. The trunk's new channels get a
    /// fresh initialisation and zero weights into the old channels, so the old channels
    /// compute what they did. The projection `out8` keeps every old channel in its group
    /// (groups are runs of `c8 / groups` channels), scaled by `sqrt(new / old per group)` so
    /// that the group's mean product is unchanged; its new channels start small and random
    /// (zero would be a saddle: a pair product's gradient is the other camera's feature).
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when `c8` is narrower than today's width or either width is
    /// not a multiple of `groups`.
    pub fn widen8(self, c8: usize, groups: usize, device: &Device) -> Result<Self, NetError> {
        let [old, c4] = {
            let [out, input, _, _] = self.down8.conv.weight.dims();
            [out, input]
        };
        if c8 < old || groups == 0 || !c8.is_multiple_of(groups) || !old.is_multiple_of(groups) {
            return Err(NetError::InvalidConfig {
                field: "cascade.feature_channels",
                message: format!(
                    "the stride-8 features can only widen from {old} channels to a multiple of \
                     the {groups} groups, got {c8}"
                ),
            });
        }
        if c8 == old {
            return Ok(self);
        }
        let c2 = self.out2.conv.weight.dims()[0];
        let fresh = Self::new([c2, c4, c8], self.ctx8.len() / 2, device);
        let widen = |block: ConvBn2d, fresh: ConvBn2d| widen_block(block, fresh, old);
        let res8 = self
            .res8
            .into_iter()
            .zip(fresh.res8)
            .map(|(b, f)| widen(b, f))
            .collect();
        let ctx8 = self
            .ctx8
            .into_iter()
            .zip(fresh.ctx8)
            .map(|(b, f)| widen(b, f))
            .collect();
        Ok(Self {
            conv0: self.conv0,
            conv2: self.conv2,
            out2: self.out2,
            down4: self.down4,
            res4: self.res4,
            out4: self.out4,
            down8: widen_block(self.down8, fresh.down8, old),
            res8,
            ctx8,
            out8: widen_projection(self.out8, fresh.out8, old, groups),
        })
    }

    /// `[B, 1, H_I, W_I]` -> features at strides 2, 4 and 8.
    pub fn forward(&self, image: Tensor<4>) -> [Tensor<4>; 3] {
        let x = self.conv0.forward(image, None); // [B, c2, H_I/2, W_I/2]
        let x = self.conv2.forward(x, None); // [B, c2, H_I/2, W_I/2]
        let f2 = self.out2.forward(x.clone(), None);
        let x = self.down4.forward(x, None); // [B, c4, H_I/4, W_I/4]
        let x = Self::residual_pairs(&self.res4, x);
        let f4 = self.out4.forward(x.clone(), None);
        let x = self.down8.forward(x, None); // [B, c8, H_I/8, W_I/8]
        let x = Self::residual_pairs(&self.res8, x);
        let x = Self::residual_pairs(&self.ctx8, x);
        let f8 = self.out8.forward(x, None);
        [f2, f4, f8]
    }
}

/// Scale of the widened projection's new channels against a fresh initialisation.
const NEW_PROJECTION_SCALE: f32 = 0.1;

/// `old` widened to the shape of `fresh` (same kernel, more output and maybe more input
/// channels): the old outputs read the old inputs as before and the new inputs with zero
/// weights; the new outputs, their bias and batch norm are `fresh`'s (whose first `old`
/// outputs are dropped). `old_width` is the old number of output channels, and of input
/// channels too when those grew.
fn widen_block(old: ConvBn2d, fresh: ConvBn2d, old_width: usize) -> ConvBn2d {
    let weight = old.conv.weight.val(); // [O, I, k, k]
    let [o, i, kh, kw] = weight.dims();
    let new_weight = fresh.conv.weight.val(); // [O', I', k, k]
    let [n_out, n_in, _, _] = new_weight.dims();
    debug_assert_eq!(o, old_width);
    let device = weight.device();
    let top = if n_in > i {
        Tensor::cat(
            vec![weight, Tensor::zeros([o, n_in - i, kh, kw], &device)],
            1,
        )
    } else {
        weight
    };
    let weight = Tensor::cat(vec![top, new_weight.narrow(0, o, n_out - o)], 0);
    let tail =
        |old: Tensor<1>, fresh: Tensor<1>| Tensor::cat(vec![old, fresh.narrow(0, o, n_out - o)], 0);
    let mut conv = fresh.conv;
    conv.weight = Param::from_tensor(weight.detach());
    conv.bias = match (old.conv.bias, conv.bias) {
        (Some(b), Some(f)) => Some(Param::from_tensor(tail(b.val(), f.val()).detach())),
        (_, f) => f,
    };
    let bn = match (old.bn, fresh.bn) {
        (Some(b), Some(mut f)) => {
            f.gamma = Param::from_tensor(tail(b.gamma.val(), f.gamma.val()).detach());
            f.beta = Param::from_tensor(tail(b.beta.val(), f.beta.val()).detach());
            f.running_mean = burn::module::RunningState::new(tail(
                b.running_mean.value(),
                f.running_mean.value(),
            ));
            f.running_var =
                burn::module::RunningState::new(tail(b.running_var.value(), f.running_var.value()));
            Some(f)
        }
        (_, f) => f,
    };
    ConvBn2d {
        conv,
        bn,
        relu: old.relu,
        host: None,
    }
}

/// The stride-8 projection widened group by group (see [`CascadeFeatures::widen8`]): new
/// channel `g r + j` is old channel `g q + j` for `j < q` (times `sqrt(r / q)`, zero weights
/// on the new inputs), a fresh channel times [`NEW_PROJECTION_SCALE`] otherwise, where `q`
/// and `r` are the old and new channels per group.
fn widen_projection(old: ConvBn2d, fresh: ConvBn2d, old_width: usize, groups: usize) -> ConvBn2d {
    let weight = old.conv.weight.val(); // [q G, q G, 1, 1]
    let [_, i, kh, kw] = weight.dims();
    let new_weight = fresh.conv.weight.val(); // [r G, r G, 1, 1]
    let [n_out, n_in, _, _] = new_weight.dims();
    let device = weight.device();
    let (q, r) = (old_width / groups, n_out / groups);
    let keep = ((r as f64) / (q as f64)).sqrt() as f32;
    let old_weight = Tensor::cat(
        vec![
            weight,
            Tensor::zeros([old_width, n_in - i, kh, kw], &device),
        ],
        1,
    ) * keep;
    let old_bias = old.conv.bias.map(|b| b.val() * keep);
    let fresh_bias = fresh
        .conv
        .bias
        .as_ref()
        .map(|b| b.val() * NEW_PROJECTION_SCALE);
    let mut rows = Vec::with_capacity(n_out);
    let mut biases = Vec::with_capacity(n_out);
    for g in 0..groups {
        for j in 0..r {
            let (row, bias) = if j < q {
                let k = g * q + j;
                (
                    old_weight.clone().narrow(0, k, 1),
                    old_bias.clone().map(|b| b.narrow(0, k, 1)),
                )
            } else {
                let k = g * r + j;
                (
                    new_weight.clone().narrow(0, k, 1) * NEW_PROJECTION_SCALE,
                    fresh_bias.clone().map(|b| b.narrow(0, k, 1)),
                )
            };
            rows.push(row);
            biases.extend(bias);
        }
    }
    let mut conv = fresh.conv;
    conv.weight = Param::from_tensor(Tensor::cat(rows, 0).detach());
    conv.bias =
        (biases.len() == n_out).then(|| Param::from_tensor(Tensor::cat(biases, 0).detach()));
    ConvBn2d {
        conv,
        bn: None,
        relu: old.relu,
        host: None,
    }
}

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
    fn constant(channels: [usize; 2], bias: f32, device: &Device) -> Self {
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
    fn new(channels: [usize; 2], device: &Device) -> Self {
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
    fn new(
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
    fn input_conv(&mut self) -> &mut Conv2d {
        match &mut self.squeeze {
            Some(squeeze) => squeeze,
            None => &mut self.c0[0].conv,
        }
    }
}

/// A 1x1 convolution from `cin` to `cout` channels without bias ([`CoarseRegularizer::squeeze`]).
fn squeeze_conv(cin: usize, cout: usize, device: &Device) -> Conv2d {
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
    fn new(cin: usize, ch: usize, k: usize, gate: bool, device: &Device) -> Self {
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

/// Candidates of a finer pixel in [`CandidateSelector`]: the 3 x 3 coarser pixels around its
/// parent.
pub const UPSAMPLE_TAPS: usize = 9;
/// Finer pixels per coarser pixel (2 x 2: each stage doubles rows and columns).
const UPSAMPLE_CHILDREN: usize = 4;
/// The starting logit of a neighbour that bilinear upsampling does not use: together such
/// taps start with under 5 % of a child's weight. Low enough to start near the bilinear
/// answer, high enough for training to reach them.
const UNUSED_TAP_LOGIT: f32 = -5.0;

/// Learnt upsampling of a stage's answer to the next grid (`convex_upsampling`): every pixel
/// of the finer grid weighs the answers of the 3 x 3 coarser pixels around its parent (its
/// candidates) by a softmax of logits that this module reads from the matching evidence at
/// each candidate (the finer stage's group-wise correlation, visibility and photometric cue
/// at the candidate's inverse depth, `[1, (G + 2) x 9, H, W]` folded), plus the logits of the
/// bilinear weights ([`bilinear_prior`]). A 3x3 convolution with ReLU (no batch norm), then
/// a 1x1 one with zero weights and biases: it starts as the bilinear resampling (within
/// the 5 % its unused taps keep).
#[derive(Module, Debug)]
pub struct CandidateSelector {
    /// 3x3 convolution (circular in longitude) with ReLU.
    pub hidden: PanoConv2d,
    /// 1x1 convolution to one logit per candidate.
    pub out: Conv2d,
}

impl CandidateSelector {
    fn new(channels: [usize; 2], device: &Device) -> Self {
        let hidden = PanoConv2d {
            conv: Conv2dConfig::new(channels, [3, 3])
                .with_padding(PaddingConfig2d::Explicit(1, 0, 1, 0))
                .init(device),
            bn: None,
            relu: true,
            host: None,
        };
        let out = Conv2dConfig::new([channels[1], UPSAMPLE_TAPS], [1, 1])
            .with_initializer(Initializer::Zeros)
            .init(device);
        Self { hidden, out }
    }

    /// A new selector for the grid of refinement stage `i` (0: half, 1: full resolution) of a
    /// network with `params`: its evidence is that stage's groups, the visibility and, with the
    /// cue, the cue at each candidate; its hidden width the stage's.
    fn for_stage(params: &CascadeParams, i: usize, device: &Device) -> Self {
        let extra = 1 + usize::from(params.zncc_cue);
        Self::new(
            [
                (params.groups[1 - i] + extra) * UPSAMPLE_TAPS,
                params.stage_channels[i],
            ],
            device,
        )
    }

    /// Its 3x3 convolution also on the host ([`PanoConv2d::with_host_conv`]).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            hidden: self.hidden.with_host_conv(),
            out: self.out,
        }
    }

    /// The candidates' evidence `[1, C, H, W]` -> logits `[1, 9, H, W]` (before the prior).
    pub fn forward(&self, evidence: Tensor<4>) -> Tensor<4> {
        self.out.forward(self.hidden.forward(evidence))
    }
}

/// The values of the 3 x 3 coarser pixels around each finer pixel's parent, tap by tap
/// (`[9][rows x cols.len()]`, tap `(dr + 1) x 3 + (dc + 1)` for the neighbour at `(dr, dc)`):
/// `coarse` is a `rows / 2 x width` map, the finer grid has `rows` rows and `2 width`
/// columns, of which `cols`. Rows beyond the top and bottom repeat the edge; columns wrap.
pub fn upsampling_candidates(
    coarse: &[f32],
    coarse_dims: [usize; 2],
    cols: &std::ops::Range<usize>,
) -> Vec<f32> {
    neighbourhood_candidates(coarse, coarse_dims, 2, cols)
}

/// [`upsampling_candidates`] for a grid `factor` (1 or 2) times finer than `coarse`'s: with
/// 1 (`same_grid_selector`) each pixel is its own parent, and tap 4 is its own value.
pub fn neighbourhood_candidates(
    coarse: &[f32],
    [coarse_rows, coarse_cols]: [usize; 2],
    factor: usize,
    cols: &std::ops::Range<usize>,
) -> Vec<f32> {
    let rows = factor * coarse_rows;
    let n = rows * cols.len();
    let mut out = vec![0.0f32; UPSAMPLE_TAPS * n];
    for r in 0..rows {
        for (i, c) in cols.clone().enumerate() {
            let (pr, pc) = (r / factor, c / factor);
            for dr in 0..3 {
                let rr = (pr + dr).saturating_sub(1).min(coarse_rows - 1);
                for dc in 0..3 {
                    let cc = (pc + coarse_cols + dc - 1) % coarse_cols;
                    out[(dr * 3 + dc) * n + r * cols.len() + i] = coarse[rr * coarse_cols + cc];
                }
            }
        }
    }
    out
}

/// The logits of the bilinear weights (`bilinear_logits`) laid out for a finer grid of
/// `rows` rows over columns `cols`: `[1, 9, rows, cols.len()]`, each pixel its child's
/// (row and column parity).
pub fn bilinear_prior(rows: usize, cols: &std::ops::Range<usize>, device: &Device) -> Tensor<4> {
    let logits = bilinear_logits();
    let n = rows * cols.len();
    let mut out = vec![0.0f32; UPSAMPLE_TAPS * n];
    for r in 0..rows {
        for (i, c) in cols.clone().enumerate() {
            let child = (r % 2) * 2 + c % 2;
            for tap in 0..UPSAMPLE_TAPS {
                out[tap * n + r * cols.len() + i] = logits[tap * UPSAMPLE_CHILDREN + child];
            }
        }
    }
    Tensor::from_data(
        TensorData::new(out, [1, UPSAMPLE_TAPS, rows, cols.len()]),
        device,
    )
}

/// The prior logits of a selector on the coarse grid itself (`same_grid_selector`),
/// `[1, 9, rows, cols.len()]`: 0 for the pixel's own answer (tap 4), [`UNUSED_TAP_LOGIT`] for
/// its 8 neighbours', so that a grown selector starts at the pixel's own answer (the
/// neighbours together keep about 5 % of the weight).
pub fn same_grid_prior(rows: usize, cols: &std::ops::Range<usize>, device: &Device) -> Tensor<4> {
    let n = rows * cols.len();
    let mut out = vec![UNUSED_TAP_LOGIT; UPSAMPLE_TAPS * n];
    out[UPSAMPLE_TAPS / 2 * n..(UPSAMPLE_TAPS / 2 + 1) * n].fill(0.0);
    Tensor::from_data(
        TensorData::new(out, [1, UPSAMPLE_TAPS, rows, cols.len()]),
        device,
    )
}

/// The logits whose softmax is close to the weights of the bilinear resampling of
/// [`omnimvs_sweep::resample_map`], channel `tap x 4 + child`: tap `(dr + 1) x 3 + (dc + 1)`
/// for the neighbour at `(dr, dc)`, child `a x 2 + b` for the finer pixel at row `2r + a`,
/// column `2c + b`. In longitude a finer grid's column `2c` lies on its parent and `2c + 1`
/// halfway to the next one (weights 1, and 1/2 and 1/2); in latitude the grids share their
/// first and last rows, so a child's offset from its parent drifts from 0 to half a row over
/// the grid: the start takes the middle's, a quarter row (3/4 for the parent's row, 1/4 for
/// the next one toward the child), and training corrects the rest.
fn bilinear_logits() -> [f32; UPSAMPLE_TAPS * UPSAMPLE_CHILDREN] {
    bilinear_weights().map(|w| if w > 0.0 { w.ln() } else { UNUSED_TAP_LOGIT })
}

/// The weights [`bilinear_logits`] starts near (same layout; zero for the unused taps).
fn bilinear_weights() -> [f32; UPSAMPLE_TAPS * UPSAMPLE_CHILDREN] {
    // d: 0, 1, 2 for offsets -1, 0, +1.
    let along_rows = |child: usize, d: usize| -> f32 {
        match (child, d) {
            (_, 1) => 0.75,
            (0, 0) | (1, 2) => 0.25,
            _ => 0.0,
        }
    };
    let along_cols = |child: usize, d: usize| -> f32 {
        match (child, d) {
            (0, 1) => 1.0,
            (1, 1 | 2) => 0.5,
            _ => 0.0,
        }
    };
    let mut weights = [0.0; UPSAMPLE_TAPS * UPSAMPLE_CHILDREN];
    for (tap, (dr, dc)) in (0..3)
        .flat_map(|dr| (0..3).map(move |dc| (dr, dc)))
        .enumerate()
    {
        for (child, (a, b)) in [(0, 0), (0, 1), (1, 0), (1, 1)].into_iter().enumerate() {
            weights[tap * UPSAMPLE_CHILDREN + child] = along_rows(a, dr) * along_cols(b, dc);
        }
    }
    weights
}

/// The convex combination of a stage's candidates: `softmax(logits)` over the candidates
/// `[1, K, H, W]` times their values `[1, K, H, W]`, summed: `[1, H, W]`.
pub fn convex_combination(logits: Tensor<4>, candidates: Tensor<4>) -> Tensor<3> {
    (softmax(logits, 1) * candidates).sum_dim(1).squeeze_dim(1)
}

/// Folds a stage's volume `[B, G + 1, K, H, W]` into 2D channels `[B, (G + 1) K, H, W]`.
fn fold_volume(volume: Tensor<5>) -> Tensor<4> {
    let [b, c, k, h, w] = volume.dims();
    volume.reshape([b, c * k, h, w])
}

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
                p.coarse_squeeze,
                p.coarse_spheres,
                p.coarse_channels,
                device,
            ),
            mid: StageRegularizer::new(
                p.stage_evidence_channels(0) * p.stage_hypotheses_of(0),
                p.stage_channels[0],
                p.stage_hypotheses_of(0),
                p.stage_gates,
                device,
            ),
            fine: StageRegularizer::new(
                p.stage_evidence_channels(1) * p.stage_hypotheses_of(1),
                p.stage_channels[1],
                p.stage_hypotheses_of(1),
                p.stage_gates,
                device,
            ),
            up_mid: p
                .half_grid_selector()
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

    /// The network with the photometric cue switched on (`zncc_cue`): the first convolution
    /// of every stage gets the cue's input channels (one per hypothesis, after the existing
    /// ones) with zero weights, so it answers exactly as before until training moves them.
    /// A network that has the cue already is returned as it is.
    #[must_use]
    pub fn with_zncc_cue(mut self) -> Self {
        if self.config.cascade.zncc_cue {
            return self;
        }
        let p = &self.config.cascade;
        let ks = [
            p.coarse_spheres,
            p.stage_hypotheses[0],
            p.stage_hypotheses[1],
        ];
        // The coarse stage's cue goes before its stride-4 correlation (`coarse_stride4`).
        let tail = self.coarse_stride4_inputs();
        insert_zero_inputs(self.coarse.input_conv(), tail, ks[0]);
        let mut firsts = vec![
            (&mut self.mid.convs[0], ks[1]),
            (&mut self.fine.convs[0], ks[2]),
        ];
        for selector in [&mut self.up_mid, &mut self.up_fine].into_iter().flatten() {
            firsts.push((&mut selector.hidden, UPSAMPLE_TAPS));
        }
        for (first, k) in firsts {
            append_zero_inputs(&mut first.conv, k);
        }
        self.config.cascade.zncc_cue = true;
        self
    }

    /// The network with the coarse stage's aggregated cue switched on (`coarse_cue_sgm`; the
    /// network must have `zncc_cue`): the coarse stage's first convolution gets one input
    /// channel per sphere, after the existing ones, with zero weights, so that it answers
    /// exactly as before until training moves them. A network that has it is returned as it is.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when the network has no `zncc_cue`.
    pub fn with_coarse_cue_sgm(self) -> Result<Self, NetError> {
        let tail = self.coarse_stride4_inputs();
        self.with_cue_channel(
            |p| &mut p.coarse_cue_sgm,
            |net| net.coarse.input_conv(),
            |p| p.coarse_spheres,
            tail,
        )
    }

    /// The input channels of the coarse stage's first convolution that read the stride-4
    /// correlation (`coarse_stride4`; the last ones): `groups[1]` per sphere, or 0.
    fn coarse_stride4_inputs(&self) -> usize {
        let p = &self.config.cascade;
        p.coarse_stride4_groups() * p.coarse_spheres
    }

    /// The network with the half-resolution stage's aggregated cue switched on
    /// (`mid_cue_sgm`; the network must have `zncc_cue` with `coarse_cue_oversample: 2`): the
    /// stage's first convolution gets one input channel per hypothesis, after the existing
    /// ones, with zero weights, so that it answers exactly as before until training moves
    /// them. A network that has it is returned as it is.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when the network cannot have it.
    pub fn with_mid_cue_sgm(self) -> Result<Self, NetError> {
        self.with_cue_channel(
            |p| &mut p.mid_cue_sgm,
            |net| &mut net.mid.convs[0].conv,
            |p| p.stage_hypotheses[0],
            0,
        )
    }

    /// The network with the cue channel that `flag` switches on: unless it is on already, the
    /// configuration with it must validate, and the convolution `first` reads `k` more input
    /// channels (one per hypothesis of its stage) with zero weights, before its last `tail`.
    fn with_cue_channel(
        mut self,
        flag: fn(&mut CascadeParams) -> &mut bool,
        first: fn(&mut Self) -> &mut Conv2d,
        k: fn(&CascadeParams) -> usize,
        tail: usize,
    ) -> Result<Self, NetError> {
        let mut config = self.config.clone();
        if *flag(&mut config.cascade) {
            return Ok(self);
        }
        *flag(&mut config.cascade) = true;
        config.validate()?;
        insert_zero_inputs(first(&mut self), tail, k(&config.cascade));
        self.config = config;
        Ok(self)
    }

    /// The network with the two neighbour hypotheses of refinement stage `stage` (1: half,
    /// 2: full resolution) within `radius` pixels (`neighbour_hypotheses`): the stage's first
    /// convolution reads their evidence (after all of the evenly spaced hypotheses') with zero
    /// weights, and its scoring convolution scores them with zero weights and a bias of
    /// `neighbour_start_score` (by default -5: the network answers nearly as before, the two
    /// holding a small share of each pixel's weight, until training moves them). A stage that
    /// has them already takes the new radius.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] for another stage, a radius of 0 for a stage that has them,
    /// or when the configuration with them is not valid.
    pub fn with_neighbour_hypotheses(
        mut self,
        stage: usize,
        radius: usize,
    ) -> Result<Self, NetError> {
        if !(1..=2).contains(&stage) {
            return Err(NetError::InvalidConfig {
                field: "neighbour_hypotheses",
                message: format!("stage {stage}: the refinement stages are 1 and 2"),
            });
        }
        let i = stage - 1;
        let mut config = self.config.clone();
        let had = config.cascade.neighbour_count(i) > 0;
        config.cascade.neighbour_hypotheses[i] = radius;
        config.validate()?;
        if had && radius == 0 {
            return Err(NetError::InvalidConfig {
                field: "neighbour_hypotheses",
                message: format!("stage {stage} has them already; they cannot be taken out"),
            });
        }
        if !had && radius > 0 {
            let p = &config.cascade;
            let channels = p.stage_evidence_channels(i);
            let regularizer = if stage == 1 {
                &mut self.mid
            } else {
                &mut self.fine
            };
            append_zero_inputs(&mut regularizer.convs[0].conv, 2 * channels);
            // Scores leave the stage times `neighbour_gain`: the bias starts at score / gain.
            let score = (p.neighbour_start_score / p.neighbour_gain) as f32;
            append_zero_outputs(&mut regularizer.out.conv, 2, score);
        }
        self.config = config;
        Ok(self)
    }

    /// The network with its stride-8 features widened to `c8` channels (see
    /// [`CascadeFeatures::widen8`]): it answers as before but for a small perturbation of
    /// the coarse correlation, and the coarse stage can learn from the new channels.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when `c8` is narrower than the network's stride-8 width, not
    /// a multiple of its coarse groups, or the widened configuration is not valid.
    pub fn with_coarse_feature_channels(mut self, c8: usize) -> Result<Self, NetError> {
        let mut config = self.config.clone();
        config.cascade.feature_channels[2] = c8;
        config.validate()?;
        let device = self.features.out8.conv.weight.val().device();
        self.features = self
            .features
            .widen8(c8, config.cascade.groups[2], &device)?;
        self.config = config;
        Ok(self)
    }

    /// The network with the coarse stage also correlating the stride-4 features
    /// (`coarse_stride4`): its first convolution reads `groups[1]` more channels per sphere,
    /// after all of the others, with zero weights, so that it answers exactly as before until
    /// training moves them. A network that has them is returned as it is.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when the configuration with them is not valid.
    pub fn with_coarse_stride4(mut self) -> Result<Self, NetError> {
        if self.config.cascade.coarse_stride4 {
            return Ok(self);
        }
        let mut config = self.config.clone();
        config.cascade.coarse_stride4 = true;
        config.validate()?;
        self.config = config;
        let inputs = self.coarse_stride4_inputs();
        append_zero_inputs(self.coarse.input_conv(), inputs);
        Ok(self)
    }

    /// The network with its coarse stage moved to the grid `scale` times coarser than the
    /// output (`coarse_scale`) and over `spheres` spheres (`coarse_spheres`), from a trained
    /// one: every weight is kept but the coarse stage's first convolution, which reads each
    /// evidence channel per sphere, and its scoring convolution, which writes one score per
    /// sphere. Those are resampled along the spheres ([`sphere_resampling`]): the new first
    /// convolution gives the old one's output for evidence that varies linearly over inverse
    /// depth, and each new score is the old scores interpolated at the new sphere's inverse
    /// depth. The 2D convolutions keep their kernels, now over pixels half the size with
    /// `scale` 2; with `scale` 2 the half grid's selector (`up_mid`) goes: the half stage
    /// centres on the coarse answer itself. A starting point for training, not an answer.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when the configuration with them is not valid.
    pub fn with_coarse_grid(mut self, scale: usize, spheres: usize) -> Result<Self, NetError> {
        let mut config = self.config.clone();
        let old = config.cascade.coarse_spheres;
        config.cascade.coarse_scale = scale;
        config.cascade.coarse_spheres = spheres;
        config.validate()?;
        if spheres != old {
            let n = config.num_invdepth;
            let conv = self.coarse.input_conv();
            conv.weight = Param::from_tensor(resample_axis(
                conv.weight.val(),
                1,
                &sphere_resampling(old, spheres, n, true),
                spheres,
            )?);
            let out = &mut self.coarse.out.conv;
            let to_new = sphere_resampling(old, spheres, n, false);
            out.weight = Param::from_tensor(resample_axis(out.weight.val(), 0, &to_new, spheres)?);
            if let Some(bias) = out.bias.take() {
                let bias = bias.val().reshape([old, 1, 1, 1]);
                let bias = resample_axis(bias, 0, &to_new, spheres)?;
                out.bias = Some(Param::from_tensor(bias.reshape([spheres])));
            }
        }
        if !config.cascade.half_grid_selector() || scale != self.config.cascade.coarse_scale {
            // A selector that upsampled 40 x 160 does not choose on the half grid.
            self.up_mid = None;
        }
        self.config = config;
        Ok(self)
    }

    /// The network with its half stage centred on a learnt choice among the 3 x 3 coarse
    /// answers around each pixel (`same_grid_selector`; the coarse stage on the half grid):
    /// a new selector whose last convolution has zero weights, so that it starts at each
    /// pixel's own answer (the 8 neighbours keeping about 5 % of the weight,
    /// [`same_grid_prior`]). A network that has it is returned as it is.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] unless the network has `coarse_scale` 2 and
    /// `convex_upsampling`.
    pub fn with_same_grid_selector(mut self) -> Result<Self, NetError> {
        if self.config.cascade.same_grid_selector && self.up_mid.is_some() {
            return Ok(self);
        }
        let mut config = self.config.clone();
        config.cascade.same_grid_selector = true;
        config.validate()?;
        let device = self.coarse.out.conv.weight.val().device();
        self.up_mid = Some(CandidateSelector::for_stage(&config.cascade, 0, &device));
        self.config = config;
        Ok(self)
    }

    /// The network with its coarse evidence squeezed through `channels` channels
    /// (`coarse_squeeze`) before the first 3x3 convolution, from a trained one. That
    /// convolution's weights `W[o, i, y, x]`, as a matrix with a row per `(o, y, x)` and a
    /// column per input `i`, are replaced by their best approximation of rank `channels` (a
    /// truncated SVD `U S V^T`, the largest singular values kept): the squeeze, a 1x1
    /// convolution without bias, takes `V^T`, and the 3x3 convolution reads its `channels`
    /// outputs through `U S`, keeping its bias and batch norm. With `channels` at least the
    /// matrix's rank the network answers as before up to rounding; below it, as nearly as
    /// a layer of that rank can. A network with that squeeze, or with none when `channels` is
    /// 0, is returned as it is.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when `channels` is more than the evidence channels, or the
    /// network has a squeeze of another width (a squeeze is not undone); [`NetError::Shape`]
    /// when the weights cannot be read.
    pub fn with_coarse_squeeze(mut self, channels: usize) -> Result<Self, NetError> {
        let have = self.config.cascade.coarse_squeeze;
        if have == channels {
            return Ok(self);
        }
        if have != 0 {
            return Err(NetError::InvalidConfig {
                field: "cascade.coarse_squeeze",
                message: format!(
                    "cannot squeeze to {channels} channels a network whose squeeze has {have}: \
                     factorise a network without one"
                ),
            });
        }
        let mut config = self.config.clone();
        config.cascade.coarse_squeeze = channels;
        config.validate()?;
        let first = &mut self.coarse.c0[0].conv;
        let weight = first.weight.val();
        let device = weight.device();
        let [outputs, inputs, kh, kw] = weight.dims();
        let values = read_values(weight, "coarse stage weights")?;
        let taps = kh * kw;
        let rows = outputs * taps;
        // M[(o, y, x), i] = W[o, i, y, x].
        let mut m = nalgebra::DMatrix::<f64>::zeros(rows, inputs);
        for o in 0..outputs {
            for i in 0..inputs {
                for t in 0..taps {
                    m[(o * taps + t, i)] = f64::from(values[(o * inputs + i) * taps + t]);
                }
            }
        }
        let svd = m.svd(true, true);
        let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
            return Err(NetError::Shape {
                what: "SVD of the coarse stage's first convolution".into(),
                expected: vec![rows, inputs],
                actual: vec![],
            });
        };
        // `svd` sorts the singular values in descending order: the first `channels` are the
        // largest. Ranks beyond the matrix's own get zero weights on both sides.
        let mut three = vec![0f32; outputs * channels * taps]; // [o, k, y, x] = U S
        let mut squeeze = vec![0f32; channels * inputs]; // [k, i] = V^T
        for (k, &sigma) in svd.singular_values.iter().take(channels).enumerate() {
            for o in 0..outputs {
                for t in 0..taps {
                    three[(o * channels + k) * taps + t] = (u[(o * taps + t, k)] * sigma) as f32;
                }
            }
            for i in 0..inputs {
                squeeze[k * inputs + i] = v_t[(k, i)] as f32;
            }
        }
        first.weight = Param::from_tensor(Tensor::from_data(
            TensorData::new(three, [outputs, channels, kh, kw]),
            &device,
        ));
        let mut conv = squeeze_conv(inputs, channels, &device);
        conv.weight = Param::from_tensor(Tensor::from_data(
            TensorData::new(squeeze, [channels, inputs, 1, 1]),
            &device,
        ));
        self.coarse.squeeze = Some(conv);
        self.config = config;
        Ok(self)
    }

    /// Group-wise correlation of one stage: every camera's features `[1, C, rows, cols]`
    /// sampled at the stage's positions, then the mean product over camera pairs that see a
    /// sample, by groups of channels, and the share of cameras that see it:
    /// `[1, groups + 1, K, H, W]`.
    ///
    /// The features are gathered channels-last (`[rows * cols, C]` rows picked by the taps),
    /// so every tap reads `C` contiguous values; the camera-pair products come from two sums,
    /// `((sum f)^2 - sum f^2) / 2`, linear in the number of cameras.
    ///
    /// # Errors
    /// [`NetError::Shape`] when there are no features, their number differs from the taps'
    /// cameras, or the batch is not 1.
    pub fn correlation(
        features: &[Tensor<4>],
        taps: &StageTaps,
        groups: usize,
    ) -> Result<Tensor<5>, NetError> {
        let shape_error = |expected: Vec<usize>, actual: Vec<usize>| NetError::Shape {
            what: "feature maps of a cascade stage".into(),
            expected,
            actual,
        };
        if let Some(host) = &taps.host {
            let Some(device) = features.first().map(Tensor::device) else {
                return Err(shape_error(vec![host.cameras.len()], vec![0]));
            };
            let dims = [taps.num_hypotheses(), taps.height(), taps.width()];
            return super::host::correlation(features, host, dims, groups, &device);
        }
        if features.is_empty() || features.len() != taps.cameras.len() {
            return Err(shape_error(vec![taps.cameras.len()], vec![features.len()]));
        }
        let [k, h, w] = [taps.num_hypotheses(), taps.height(), taps.width()];
        let mut sum: Option<Tensor<2>> = None;
        let mut sum_sq: Option<Tensor<2>> = None;
        let mut channels = 0;
        for (feature, cam) in features.iter().zip(&taps.cameras) {
            let [b, c, rows, cols] = feature.dims();
            if b != 1 {
                return Err(shape_error(vec![1, c, rows, cols], vec![b, c, rows, cols]));
            }
            channels = c;
            let table = feature.clone().reshape([c, rows * cols]).swap_dims(0, 1); // [P, C]
            let warped = gather_rows(table, cam); // [S, C]
            let sq = warped.clone().powi_scalar(2);
            sum = Some(match sum {
                Some(s) => s + warped,
                None => warped,
            });
            sum_sq = Some(match sum_sq {
                Some(s) => s + sq,
                None => sq,
            });
        }
        let (Some(sum), Some(sum_sq)) = (sum, sum_sq) else {
            return Err(shape_error(vec![1], vec![0]));
        };
        let samples = k * h * w;
        let pairs = (sum.powi_scalar(2) - sum_sq).div_scalar(2.0); // [S, C]
        let grouped = pairs
            .reshape([samples, groups, channels / groups])
            .mean_dim(2) // [S, G, 1]
            .reshape([samples, groups])
            / taps
                .pair_count
                .clone()
                .reshape([samples, 1])
                .clamp_min(1e-3); // [S, G]
        let corr = grouped
            .swap_dims(0, 1) // [G, S]
            .reshape([1, groups, k, h, w]); // [1, G, K, H, W]
        let seen = taps.visibility.clone(); // [1, 1, K, H, W]
        Ok(Tensor::cat(vec![corr, seen], 1)) // [1, G+1, K, H, W]
    }

    /// Softmax of a stage's scores and the expected index over its hypotheses
    /// `[1 or B, K, H, W]` (`N` units).
    pub fn soft_argmax(scores: Tensor<4>, hypotheses: Tensor<4>) -> StageOutput {
        let prob = softmax(scores, 1); // [B, K, H, W]
        let index = (prob.clone() * hypotheses.clone())
            .sum_dim(1)
            .squeeze_dim(1); // [B, H, W]
        StageOutput {
            prob,
            index,
            hypotheses,
        }
    }

    /// A stage's volume `[1, G + 1, K, H, W]` with the photometric cue `[1, C, K, H, W]`
    /// appended when the network has it (`[1, G + 1 + C, K, H, W]`), as it is otherwise; `C`
    /// is `channels` (2 for a coarse stage with `coarse_cue_sgm`, else 1).
    ///
    /// # Errors
    /// [`NetError::Shape`] when the network has the cue and it is missing or of another shape.
    fn with_cue(
        &self,
        volume: Tensor<5>,
        cue: Option<Tensor<5>>,
        taps: &StageTaps,
        channels: usize,
    ) -> Result<Tensor<5>, NetError> {
        if !self.config.cascade.zncc_cue {
            return Ok(volume);
        }
        let expected = [
            1,
            channels,
            taps.num_hypotheses(),
            taps.height(),
            taps.width(),
        ];
        let actual = cue.as_ref().map_or(vec![0], |c| c.dims().to_vec());
        match cue {
            Some(cue) if cue.dims() == expected => Ok(Tensor::cat(vec![volume, cue], 1)),
            _ => Err(NetError::Shape {
                what: "photometric cue of a stage (the network has `zncc_cue`)".into(),
                expected: expected.to_vec(),
                actual,
            }),
        }
    }

    /// Coarse stage from the stride-8 features of every camera and, with `zncc_cue`, the
    /// photometric cue at its samples; with `coarse_stride4`, `stride4` gives the stride-4
    /// features and their taps at the same samples, whose group-wise correlation (without a
    /// second visibility) follows everything else.
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`]; a missing cue, or stride-4 features missing where the
    /// network reads them (or given where it does not).
    pub fn coarse_stage(
        &self,
        features: &[Tensor<4>],
        taps: &StageTaps,
        cue: Option<Tensor<5>>,
        stride4: Option<(&[Tensor<4>], &StageTaps)>,
    ) -> Result<StageOutput, NetError> {
        let p = &self.config.cascade;
        let volume = Self::correlation(features, taps, p.groups[2])?;
        let channels = 1 + usize::from(p.coarse_cue_sgm);
        let mut volume = self.with_cue(volume, cue, taps, channels)?;
        match (p.coarse_stride4, stride4) {
            (false, None) => {}
            (true, Some((features4, taps4))) => {
                let fine = Self::correlation(features4, taps4, p.groups[1])?;
                let fine = fine.narrow(1, 0, p.groups[1]); // the visibility is there already
                volume = Tensor::cat(vec![volume, fine], 1);
            }
            (has, given) => {
                return Err(NetError::Shape {
                    what: "stride-4 features of the coarse stage (`coarse_stride4`)".into(),
                    expected: vec![usize::from(has)],
                    actual: vec![usize::from(given.is_some())],
                });
            }
        }
        let scores = self.coarse.forward(fold_volume(volume)); // [B, K, H, W]
        Ok(Self::soft_argmax(scores, taps.hypotheses.clone()))
    }

    /// A refinement stage (`level` 1: half resolution from stride-4 features, 0: full
    /// resolution from stride-2 features).
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`].
    pub fn refine_stage(
        &self,
        level: usize,
        features: &[Tensor<4>],
        taps: &StageTaps,
    ) -> Result<StageOutput, NetError> {
        let (scores, gate) = self.refine_scores(level, features, taps)?;
        Self::gated_answer(scores, gate, taps)
    }

    /// The learnt upsampling to the grid of refinement `level` (1: half, 0: full resolution)
    /// by that grid's `selector` ([`CascadeNet::selector`]) over `taps` whose hypotheses are
    /// the candidates of every pixel ([`upsampling_candidates`]), with `prior` the bilinear
    /// logits ([`bilinear_prior`]): `[1, H, W]`, differentiable in the selector's weights.
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`].
    pub fn select_centres(
        &self,
        level: usize,
        selector: &CandidateSelector,
        features: &[Tensor<4>],
        taps: &StageTaps,
        prior: Tensor<4>,
    ) -> Result<Tensor<3>, NetError> {
        let volume = Self::correlation(features, taps, self.config.cascade.groups[level])?;
        let volume = self.with_cue(volume, taps.cue.clone(), taps, 1)?;
        let logits = selector.forward(fold_volume(volume)) + prior; // [1, 9, H, W]
        Ok(convex_combination(logits, taps.hypotheses.clone()))
    }

    /// The learnt upsampling's selector for the grid of refinement `level` (1: half, 0: full
    /// resolution), when the network has one.
    pub fn selector(&self, level: usize) -> Option<&CandidateSelector> {
        if level == 1 {
            self.up_mid.as_ref()
        } else {
            self.up_fine.as_ref()
        }
    }

    /// A refinement stage's answer from its `scores` over the hypotheses of `taps`: the soft
    /// argmax, and with a `gate`, `centre + g (soft argmax - centre)`.
    ///
    /// # Errors
    /// [`NetError::Shape`] for a gate with taps that have no centre.
    pub fn gated_answer(
        scores: Tensor<4>,
        gate: Option<Tensor<3>>,
        taps: &StageTaps,
    ) -> Result<StageOutput, NetError> {
        let mut out = Self::soft_argmax(scores, taps.hypotheses.clone());
        if let Some(gate) = gate {
            let Some(center) = taps.center.clone() else {
                return Err(NetError::Shape {
                    what: "centre of a gated refinement stage (taps without one)".into(),
                    expected: vec![1, taps.height(), taps.width()],
                    actual: vec![0],
                });
            };
            // centre + g (answer - centre): where the gate closes, the stage keeps its centre.
            out.index = center.clone() + gate * (out.index - center); // [B, H, W]
        }
        Ok(out)
    }

    /// A refinement stage's scores over its hypotheses `[B, K, H, W]` (before the soft argmax)
    /// and, when the stage has one, its gate `[B, H, W]`.
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`].
    pub fn refine_scores(
        &self,
        level: usize,
        features: &[Tensor<4>],
        taps: &StageTaps,
    ) -> Result<(Tensor<4>, Option<Tensor<3>>), NetError> {
        let groups = self.config.cascade.groups[level];
        let volume = Self::correlation(features, taps, groups)?;
        // The half-resolution stage's cue has the aggregated channel too with `mid_cue_sgm`.
        let channels = 1 + usize::from(level == 1 && self.config.cascade.mid_cue_sgm);
        let volume = self.with_cue(volume, taps.cue.clone(), taps, channels)?;
        let regularizer = if level == 1 { &self.mid } else { &self.fine };
        // The neighbour hypotheses' evidence after all of the evenly spaced ones', and their
        // scores last; both times `neighbour_gain` (a rate of their own under Adam).
        let extra = self.config.cascade.neighbour_count(1 - level);
        if extra == 0 {
            return Ok(regularizer.forward(fold_volume(volume))); // [B, K, H, W]
        }
        let gain = self.config.cascade.neighbour_gain as f32;
        let [_, _, k, _, _] = volume.dims();
        let even = volume.clone().narrow(2, 0, k - extra);
        let mut neighbours = volume.narrow(2, k - extra, extra);
        if gain != 1.0 {
            neighbours = neighbours * gain;
        }
        let folded = Tensor::cat(vec![fold_volume(even), fold_volume(neighbours)], 1);
        let (scores, gate) = regularizer.forward(folded);
        if gain == 1.0 {
            return Ok((scores, gate));
        }
        let even = scores.clone().narrow(1, 0, k - extra);
        let neighbours = scores.narrow(1, k - extra, extra) * gain;
        Ok((Tensor::cat(vec![even, neighbours], 1), gate)) // [B, K, H, W]
    }
}

/// `conv` writing `k` more output channels, after its own, with zero weights and `bias`.
fn append_zero_outputs(conv: &mut Conv2d, k: usize, bias: f32) {
    let weight = conv.weight.val(); // [C_out, C_in, kh, kw]
    let [_, c_in, kh, kw] = weight.dims();
    let device = weight.device();
    let zeros = Tensor::zeros([k, c_in, kh, kw], &device);
    conv.weight = Param::from_tensor(Tensor::cat(vec![weight, zeros], 0).detach());
    if let Some(b) = conv.bias.take() {
        let new = Tensor::<1>::full([k], bias, &device);
        conv.bias = Some(Param::from_tensor(
            Tensor::cat(vec![b.val(), new], 0).detach(),
        ));
    }
}

/// The matrix that carries a per-sphere quantity from `from` coarse spheres to `to`
/// ([`super::sampler::coarse_indices`] over `N = num_invdepth`), row-major `[to, from]` when
/// `transpose` is false: each new sphere's value interpolated linearly between the two old
/// spheres around its inverse depth (scores). With `transpose`, `[from, to]`'s transpose laid
/// out as `[to, from]` too: the weight that a new sphere's evidence takes over from each old
/// sphere's, so that `sum_old w_old e_old = sum_new w_new e_new` whenever the old evidence is
/// the new one interpolated linearly (first-layer weights).
pub fn sphere_resampling(from: usize, to: usize, num_invdepth: usize, transpose: bool) -> Vec<f32> {
    let interpolate = |at: &[f64], grid: &[f64]| -> Vec<f32> {
        // Rows: positions `at`; columns: the `grid` spheres.
        let spacing = super::sampler::coarse_spacing(grid.len(), num_invdepth);
        let mut m = vec![0f32; at.len() * grid.len()];
        for (r, &x) in at.iter().enumerate() {
            let u = (x / spacing).clamp(0.0, (grid.len() - 1) as f64);
            let i0 = (u.floor() as usize).min(grid.len() - 1);
            let i1 = (i0 + 1).min(grid.len() - 1);
            let f = (u - i0 as f64) as f32;
            m[r * grid.len() + i0] += 1.0 - f;
            m[r * grid.len() + i1] += f;
        }
        m
    };
    let old = super::sampler::coarse_indices(from, num_invdepth);
    let new = super::sampler::coarse_indices(to, num_invdepth);
    if !transpose {
        return interpolate(&new, &old);
    }
    // Old positions from new spheres, `[from, to]`, transposed to `[to, from]`.
    let m = interpolate(&old, &new);
    let mut t = vec![0f32; to * from];
    for i in 0..from {
        for j in 0..to {
            t[j * from + i] = m[i * to + j];
        }
    }
    t
}

/// `weight` (`[O, I, kh, kw]`) with the sphere axis inside `axis` (0 or 1; that axis is
/// `groups x from` with the sphere fastest, as [`fold_volume`] lays a volume out) carried to
/// `to` spheres by `matrix` (`[to, from]`, [`sphere_resampling`]).
///
/// # Errors
/// [`NetError`] when the weights cannot be read back from the device.
fn resample_axis(
    weight: Tensor<4>,
    axis: usize,
    matrix: &[f32],
    to: usize,
) -> Result<Tensor<4>, NetError> {
    let dims = weight.dims();
    let device = weight.device();
    let values = read_values(weight, "coarse stage weights")?;
    let from = matrix.len() / to;
    let groups = dims[axis] / from;
    let mut out_dims = dims;
    out_dims[axis] = groups * to;
    // Row-major strides of `dims` and of the output.
    let inner: usize = dims[axis + 1..].iter().product();
    let outer: usize = dims[..axis].iter().product();
    let mut out = vec![0f32; outer * groups * to * inner];
    for o in 0..outer {
        for g in 0..groups {
            for j in 0..to {
                let dst = ((o * groups + g) * to + j) * inner;
                for i in 0..from {
                    let m = matrix[j * from + i];
                    if m == 0.0 {
                        continue;
                    }
                    let src = ((o * groups + g) * from + i) * inner;
                    for e in 0..inner {
                        out[dst + e] += m * values[src + e];
                    }
                }
            }
        }
    }
    Ok(Tensor::from_data(TensorData::new(out, out_dims), &device))
}

/// `first` reading `k` more input channels, after its own, with zero weights: the network
/// answers as before until training moves them.
fn append_zero_inputs(first: &mut Conv2d, k: usize) {
    insert_zero_inputs(first, 0, k);
}

/// `first` reading `k` more input channels with zero weights, placed before its last `tail`
/// input channels (after all of them with `tail` 0).
fn insert_zero_inputs(first: &mut Conv2d, tail: usize, k: usize) {
    let weight = first.weight.val(); // [C_out, C_in, 3, 3]
    let [c_out, c_in, kh, kw] = weight.dims();
    let zeros = Tensor::zeros([c_out, k, kh, kw], &weight.device());
    let head = c_in - tail.min(c_in);
    let mut parts = vec![weight.clone().narrow(1, 0, head), zeros];
    if head < c_in {
        parts.push(weight.narrow(1, head, c_in - head));
    }
    let widened = Tensor::cat(parts, 1).detach(); // a leaf again
    first.weight = Param::from_tensor(widened);
}

/// Bilinear sampling of a channels-last table `[P, C]` (`P = rows * cols` of a feature map)
/// at one camera's taps: `[S, C]`, `S` the taps' samples. Differentiable with respect to the
/// table (the gradient is a scatter-add).
fn gather_rows(table: Tensor<2>, taps: &crate::model::SweepTaps) -> Tensor<2> {
    let mut out: Option<Tensor<2>> = None;
    for (index, weight) in taps.indices.iter().zip(&taps.weights) {
        let samples = weight.dims()[1];
        let tap = table.clone().select(0, index.clone()) // [S, C]
            * weight.clone().reshape([samples, 1]); // [S, 1]
        out = Some(match out {
            Some(acc) => acc + tap,
            None => tap,
        });
    }
    let [_, c] = table.dims();
    out.unwrap_or_else(|| Tensor::zeros([0, c], &table.device()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use omnimvs_sweep::{EquirectGrid, resample_map};

    /// The learnt upsampling of a `h x w` map with the given per-child logits in place of the
    /// selector's (the bilinear prior's layout), over the finer grid's columns `cols`.
    fn upsample(
        values: &[f32],
        [h, w]: [usize; 2],
        child_logits: &[f32; 36],
        cols: std::ops::Range<usize>,
    ) -> Vec<f32> {
        let device = Device::flex();
        let n = 2 * h * cols.len();
        let candidates = upsampling_candidates(values, [h, w], &cols);
        let mut logits = vec![0.0f32; UPSAMPLE_TAPS * n];
        for r in 0..2 * h {
            for (i, c) in cols.clone().enumerate() {
                let child = (r % 2) * 2 + c % 2;
                for tap in 0..UPSAMPLE_TAPS {
                    logits[tap * n + r * cols.len() + i] = child_logits[tap * 4 + child];
                }
            }
        }
        let shape = [1, UPSAMPLE_TAPS, 2 * h, cols.len()];
        let out = convex_combination(
            Tensor::from_data(TensorData::new(logits, shape), &device),
            Tensor::from_data(TensorData::new(candidates, shape), &device),
        );
        read_values(out, "up").unwrap()
    }

    #[test]
    fn the_starting_weights_are_near_the_bilinear_resampling_along_longitude() {
        // The start puts under 5 % of every child's weight on the taps bilinear leaves out,
        // and the prior tensor lays those logits out by row and column parity.
        let start = bilinear_logits();
        let weights = bilinear_weights();
        for child in 0..UPSAMPLE_CHILDREN {
            let column = |v: &[f32; 36]| (0..9).map(|t| v[t * 4 + child]).collect::<Vec<_>>();
            let (l, w) = (column(&start), column(&weights));
            let total: f32 = l.iter().map(|x| x.exp()).sum();
            let unused: f32 = l
                .iter()
                .zip(&w)
                .filter(|(_, w)| **w == 0.0)
                .map(|(x, _)| x.exp())
                .sum();
            assert!(unused / total < 0.05, "child {child}: {}", unused / total);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
        let prior = read_values(bilinear_prior(4, &(3..7), &Device::flex()), "prior").unwrap();
        assert_eq!(prior.len(), 9 * 4 * 4);
        // Tap 4 (the parent) of the pixel at row 1, column 4 (child (1, 0)): ln(3/4 x 1).
        assert!((prior[4 * 16 + 4 + 1] - 0.75f32.ln()).abs() < 1e-6);
        // Those weights, sharpened, on a map that varies along columns only: `resample_map`
        // exactly, the wrap-around included (the last child column lies halfway to the first).
        let sharp = weights.map(|w| if w > 0.0 { w.ln() } else { -60.0 });
        let (h, w) = (4, 8);
        let values: Vec<f32> = (0..h * w).map(|i| ((i % w) * (i % w)) as f32).collect();
        let up = upsample(&values, [h, w], &sharp, 0..2 * w);
        let from = EquirectGrid::new(h, w, 45.0).unwrap();
        let to = EquirectGrid::new(2 * h, 2 * w, 45.0).unwrap();
        let expected = resample_map(&values, &from, &to);
        for (a, b) in up.iter().zip(&expected) {
            assert!((a - b).abs() < 1e-3, "{a} vs {b}");
        }
        // Along rows, a quarter row toward each child: 3/4 and 1/4; the edges repeat.
        let values: Vec<f32> = (0..h * w).map(|i| 10.0 * (i / w) as f32).collect();
        let up = upsample(&values, [h, w], &sharp, 0..2 * w);
        let at = |r: usize| up[r * 2 * w];
        assert!((at(2) - 7.5).abs() < 1e-3 && (at(3) - 12.5).abs() < 1e-3);
        assert!(at(0).abs() < 1e-3 && (at(2 * h - 1) - 30.0).abs() < 1e-3);
    }

    #[test]
    fn sharp_weights_take_one_neighbour_in_a_window_and_around_the_seam() {
        // All weight on the neighbour to the right (tap (0, +1) = 5): every child takes it,
        // the last columns the first coarse column's (the panorama wraps).
        let (h, w) = (3, 5);
        let values: Vec<f32> = (0..h * w).map(|i| (10 * (i / w) + i % w) as f32).collect();
        let mut sharp = [-30.0f32; 36];
        for child in 0..4 {
            sharp[5 * 4 + child] = 30.0;
        }
        let cols = 6..2 * w;
        let up = upsample(&values, [h, w], &sharp, cols.clone());
        for r in 0..2 * h {
            for (i, c) in cols.clone().enumerate() {
                let right = values[(r / 2) * w + (c / 2 + 1) % w];
                assert!((up[r * cols.len() + i] - right).abs() < 1e-4);
            }
        }
    }
}
