//! Convolution + batch norm + ReLU blocks with an optional residual input, laid out like the
//! reference `module/basic.py` (`conv`, `bn`) so that PyTorch state dicts load by name. The
//! 2D block also serves the cascade's panorama convolutions, which wrap around in longitude
//! ([`ConvBn2d::pano`]).

use std::sync::Arc;

use burn::module::{Module, Param};
use burn::nn::Initializer;
use burn::nn::conv::{
    Conv2d, Conv2dConfig, Conv3d, Conv3dConfig, ConvTranspose3d, ConvTranspose3dConfig,
};
use burn::nn::{BatchNorm, BatchNormConfig, PaddingConfig2d, PaddingConfig3d};
use burn::tensor::{Device, Tensor, activation};

use crate::hostconv::{HostConv, host_forward};

/// Applies the batch norm `bn` when there is one, `+ residual` when given, then ReLU when asked.
/// PyTorch adds the residual after batch norm and before ReLU.
fn finish<const D: usize>(
    x: Tensor<D>,
    bn: Option<&BatchNorm>,
    residual: Option<Tensor<D>>,
    relu: bool,
) -> Tensor<D> {
    let x = match bn {
        Some(bn) => bn.forward(x),
        None => x,
    };
    let x = match residual {
        Some(residual) => x + residual,
        None => x,
    };
    if relu { activation::relu(x) } else { x }
}

/// Per-output-channel scale and shift `(gamma / sqrt(var + eps), beta - mean * scale)` of an
/// inference-mode batch norm.
fn batch_norm_affine(bn: &BatchNorm) -> (Tensor<1>, Tensor<1>) {
    let scale = bn.gamma.val() / bn.running_var.value().add_scalar(bn.epsilon).sqrt();
    let shift = bn.beta.val() - bn.running_mean.value() * scale.clone();
    (scale, shift)
}

/// Folds an inference-mode batch norm, when there is one, into a convolution's weight (output
/// channels along `out_dim`) and bias: `w' = w * scale`, `b' = b * scale + shift`.
fn fold_into<const D: usize>(
    weight: &mut Param<Tensor<D>>,
    bias: &mut Option<Param<Tensor<1>>>,
    bn: Option<BatchNorm>,
    out_dim: usize,
) {
    let Some(bn) = bn else {
        return;
    };
    let (scale, shift) = batch_norm_affine(&bn);
    let mut shape = [1usize; D];
    shape[out_dim] = scale.dims()[0];
    let folded = weight.val() * scale.clone().reshape(shape);
    let folded_bias = match bias.as_ref() {
        Some(b) => b.val() * scale + shift,
        None => shift,
    };
    *weight = Param::from_tensor(folded);
    *bias = Some(Param::from_tensor(folded_bias));
}

/// Folds an inference-mode batch norm, when there is one, into a 2D convolution.
pub(crate) fn fold_into_conv2d(conv: &mut Conv2d, bn: Option<BatchNorm>) {
    fold_into(&mut conv.weight, &mut conv.bias, bn, 0);
}

/// 2D convolution, optional batch norm, optional ReLU; on the panorama grid
/// ([`ConvBn2d::pano`]) the input's columns are a circle.
#[derive(Module, Debug)]
pub struct ConvBn2d {
    /// The convolution (`conv` in the reference state dict).
    pub conv: Conv2d,
    /// Batch norm after the convolution (`bn`), absent for plain convolutions and after
    /// [`ConvBn2d::fold_batch_norm`].
    pub bn: Option<BatchNorm>,
    /// Whether a ReLU ends the block.
    #[module(skip)]
    pub relu: bool,
    /// Whether the input wraps around in longitude: it is padded circularly by one column on
    /// each side before the convolution, which pads no columns itself ([`ConvBn2d::pano`]).
    #[module(skip)]
    pub wrap_cols: bool,
    /// The same convolution on the host ([`ConvBn2d::with_host_conv`]: inference on a CPU).
    #[module(skip)]
    pub host: Option<Arc<HostConv>>,
}

impl ConvBn2d {
    /// A square `kernel x kernel` convolution with symmetric padding `pad`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        channels: [usize; 2],
        kernel: usize,
        stride: usize,
        pad: usize,
        dilation: usize,
        bn: bool,
        relu: bool,
        device: &Device,
    ) -> Self {
        let conv = Conv2dConfig::new(channels, [kernel, kernel])
            .with_stride([stride, stride])
            .with_dilation([dilation, dilation])
            .with_padding(PaddingConfig2d::Explicit(pad, pad, pad, pad))
            .init(device);
        let bn = bn.then(|| BatchNormConfig::new(channels[1]).init(device));
        Self {
            conv,
            bn,
            relu,
            wrap_cols: false,
            host: None,
        }
    }

    /// A 3x3 convolution on the panorama grid, which wraps around in longitude (the columns
    /// are a circle) and is zero-padded in latitude: `channels[0] -> channels[1]` with random
    /// weights and a bias, at `stride`; with `bn_relu`, a batch norm and a ReLU after the
    /// convolution. The cost regularisation works on 2D maps whose channels are (groups x
    /// hypotheses): on a CPU a 2D convolution with many channels runs near the GEMM peak,
    /// where a 3D convolution with a handful of channels over the same volume is memory-bound
    /// (measured 10x slower per FLOP with burn's flex backend, see the README).
    pub fn pano(channels: [usize; 2], stride: usize, bn_relu: bool, device: &Device) -> Self {
        Self::pano_from(
            Conv2dConfig::new(channels, [3, 3]).with_stride([stride, stride]),
            bn_relu,
            device,
        )
    }

    /// A panorama convolution ([`ConvBn2d::pano`]) whose output starts at `bias` everywhere
    /// (zero weights), no batch norm, no ReLU.
    pub fn pano_constant(channels: [usize; 2], bias: f32, device: &Device) -> Self {
        let mut block = Self::pano_from(
            Conv2dConfig::new(channels, [3, 3]).with_initializer(Initializer::Zeros),
            false,
            device,
        );
        block.conv.bias = Some(Param::from_tensor(Tensor::full(
            [channels[1]],
            bias,
            device,
        )));
        block
    }

    /// A panorama convolution with ReLU and no batch norm ([`ConvBn2d::pano`]).
    pub fn pano_relu(channels: [usize; 2], device: &Device) -> Self {
        Self {
            relu: true,
            ..Self::pano_from(Conv2dConfig::new(channels, [3, 3]), false, device)
        }
    }

    /// `config` padded by one row above and below and no column (the wrap pads those), with a
    /// batch norm and a ReLU when `bn_relu`.
    fn pano_from(config: Conv2dConfig, bn_relu: bool, device: &Device) -> Self {
        let conv = config
            .with_padding(PaddingConfig2d::Explicit(1, 0, 1, 0))
            .init(device);
        let channels = conv.weight.dims()[0];
        Self {
            conv,
            bn: bn_relu.then(|| BatchNormConfig::new(channels).init(device)),
            relu: bn_relu,
            wrap_cols: true,
            host: None,
        }
    }

    /// The block with its convolution also on the host ([`HostConv`], with the longitude wrap
    /// in its addressing), used by [`ConvBn2d::forward`] from then on: for inference on a
    /// CPU, after [`ConvBn2d::fold_batch_norm`] (a block that still has its batch norm is
    /// returned as it is).
    #[must_use]
    pub fn with_host_conv(mut self) -> Self {
        if self.bn.is_none() {
            let extra_cols = usize::from(self.wrap_cols);
            self.host = HostConv::from_conv(&self.conv, extra_cols, self.wrap_cols).map(Arc::new);
        }
        self
    }

    /// `[B, C_in, H, W] -> [B, C_out, H', W']`, adding `residual` before the ReLU.
    pub fn forward(&self, x: Tensor<4>, residual: Option<Tensor<4>>) -> Tensor<4> {
        let (x, residual) = match &self.host {
            Some(host) => match host_forward(host, x, residual, self.relu) {
                Ok(y) => return y,
                Err(declined) => *declined,
            },
            None => (x, residual),
        };
        let x = if self.wrap_cols {
            let [_, _, _, w] = x.dims();
            let first = x.clone().narrow(3, 0, 1);
            let last = x.clone().narrow(3, w - 1, 1);
            Tensor::cat(vec![last, x, first], 3) // [B, C, H, W + 2]
        } else {
            x
        };
        let x = self.conv.forward(x); // [B, C_out, H', W']
        finish(x, self.bn.as_ref(), residual, self.relu)
    }

    /// Folds an inference-mode batch norm into the convolution.
    #[must_use]
    pub fn fold_batch_norm(mut self) -> Self {
        fold_into_conv2d(&mut self.conv, self.bn.take());
        self
    }

    /// The block with its batch norm's scale at zero: as the second block of a residual pair
    /// its branch adds nothing at first, so the pair starts as the identity (on non-negative
    /// inputs, as after a ReLU) and a trained network can grow by it unchanged.
    pub fn zero_residual(mut self) -> Self {
        if let Some(bn) = self.bn.as_mut() {
            let device = bn.gamma.val().device();
            let channels = bn.gamma.val().dims()[0];
            bn.gamma = Param::from_tensor(Tensor::zeros([channels], &device));
        }
        self
    }
}

/// 3D convolution (`k x k x k`, symmetric padding), optional batch norm, optional ReLU.
#[derive(Module, Debug)]
pub struct ConvBn3d {
    /// The convolution (`conv`).
    pub conv: Conv3d,
    /// Batch norm (`bn`), absent after [`ConvBn3d::fold_batch_norm`].
    pub bn: Option<BatchNorm>,
    /// Whether a ReLU ends the block.
    #[module(skip)]
    pub relu: bool,
    /// The same convolution on the host ([`ConvBn3d::with_host_conv`]: inference on a CPU).
    #[module(skip)]
    pub host: Option<Arc<HostConv>>,
}

impl ConvBn3d {
    /// A cubic `kernel^3` convolution with padding `pad` on every side.
    pub fn new(
        channels: [usize; 2],
        kernel: usize,
        stride: usize,
        pad: usize,
        bn: bool,
        relu: bool,
        device: &Device,
    ) -> Self {
        let conv = Conv3dConfig::new(channels, [kernel; 3])
            .with_stride([stride; 3])
            .with_padding(PaddingConfig3d::Explicit(pad, pad, pad))
            .init(device);
        let bn = bn.then(|| BatchNormConfig::new(channels[1]).init(device));
        Self {
            conv,
            bn,
            relu,
            host: None,
        }
    }

    /// The block with its convolution also on the host ([`HostConv`]), used by
    /// [`ConvBn3d::forward`] from then on: for inference on a CPU, after
    /// [`ConvBn3d::fold_batch_norm`] (a block that still has its batch norm is returned as it
    /// is).
    #[must_use]
    pub fn with_host_conv(mut self) -> Self {
        if self.bn.is_none() {
            self.host = HostConv::from_conv3d(&self.conv).map(Arc::new);
        }
        self
    }

    /// `[B, C_in, D, H, W] -> [B, C_out, D', H', W']`.
    pub fn forward(&self, x: Tensor<5>, residual: Option<Tensor<5>>) -> Tensor<5> {
        let (x, residual) = match &self.host {
            Some(host) => match host_forward(host, x, residual, self.relu) {
                Ok(y) => return y,
                Err(declined) => *declined,
            },
            None => (x, residual),
        };
        let x = self.conv.forward(x); // [B, C_out, D', H', W']
        self.finish(x, residual)
    }

    /// Batch norm, residual and ReLU applied to an already convolved tensor (bias included).
    pub fn finish(&self, x: Tensor<5>, residual: Option<Tensor<5>>) -> Tensor<5> {
        finish(x, self.bn.as_ref(), residual, self.relu)
    }

    /// Folds an inference-mode batch norm into the convolution.
    pub fn fold_batch_norm(mut self) -> Self {
        fold_into(
            &mut self.conv.weight,
            &mut self.conv.bias,
            self.bn.take(),
            0,
        );
        self
    }
}

/// 3D transposed convolution, optional batch norm, optional ReLU.
#[derive(Module, Debug)]
pub struct DeconvBn3d {
    /// The transposed convolution (`conv`).
    pub conv: ConvTranspose3d,
    /// Batch norm (`bn`), absent after [`DeconvBn3d::fold_batch_norm`].
    pub bn: Option<BatchNorm>,
    /// Whether a ReLU ends the block.
    #[module(skip)]
    pub relu: bool,
}

impl DeconvBn3d {
    /// A `kernel^3` transposed convolution with padding `pad` and output padding `out_pad`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        channels: [usize; 2],
        kernel: usize,
        stride: usize,
        pad: usize,
        out_pad: usize,
        bn: bool,
        relu: bool,
        device: &Device,
    ) -> Self {
        let conv = ConvTranspose3dConfig::new(channels, [kernel; 3])
            .with_stride([stride; 3])
            .with_padding([pad; 3])
            .with_padding_out([out_pad; 3])
            .init(device);
        let bn = bn.then(|| BatchNormConfig::new(channels[1]).init(device));
        Self { conv, bn, relu }
    }

    /// `[B, C_in, D, H, W] -> [B, C_out, 2D, 2H, 2W]` for stride 2.
    pub fn forward(&self, x: Tensor<5>, residual: Option<Tensor<5>>) -> Tensor<5> {
        let x = self.conv.forward(x); // [B, C_out, D', H', W']
        finish(x, self.bn.as_ref(), residual, self.relu)
    }

    /// Folds an inference-mode batch norm into the transposed convolution, whose weight is
    /// `[C_in, C_out, k, k, k]`.
    pub fn fold_batch_norm(mut self) -> Self {
        fold_into(
            &mut self.conv.weight,
            &mut self.conv.bias,
            self.bn.take(),
            1,
        );
        self
    }
}
