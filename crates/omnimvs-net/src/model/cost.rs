//! Fusion and the 3D encoder-decoder that regularises the cost volume (Table 1).

use burn::module::Module;
use burn::tensor::module::conv3d;
use burn::tensor::ops::ConvOptions;
use burn::tensor::{Device, Tensor};

use super::blocks::{ConvBn3d, DeconvBn3d};

/// Padding of the 3x3x3 fusion convolution on every side.
const FUSION_PAD: usize = 1;

/// Fusion of the concatenated spherical features, then the encoder-decoder with skip
/// additions. State-dict keys: `cost_computes.fusion`, `cost_computes.convs.{0..14}`,
/// `cost_computes.deconv{1..5}`.
#[derive(Module, Debug)]
pub struct CostCompute {
    /// 3x3x3 fusion of `num_cameras * CH` channels into `2 CH`.
    pub fusion: ConvBn3d,
    /// 3Dconv1-15 of Table 1 (index 0 is 3Dconv1).
    pub convs: Vec<ConvBn3d>,
    /// 3Ddeconv1: `8 CH -> 4 CH`, adds 3Dconv12.
    pub deconv1: DeconvBn3d,
    /// 3Ddeconv2: `4 CH -> 4 CH`, adds 3Dconv9.
    pub deconv2: DeconvBn3d,
    /// 3Ddeconv3: `4 CH -> 4 CH`, adds 3Dconv6.
    pub deconv3: DeconvBn3d,
    /// 3Ddeconv4: `4 CH -> 2 CH`, adds 3Dconv3.
    pub deconv4: DeconvBn3d,
    /// 3Ddeconv5: `2 CH -> 1`, the full-resolution cost (no batch norm, no ReLU).
    pub deconv5: DeconvBn3d,
}

/// Intermediate activations of the encoder kept for the decoder's skip additions.
struct Skips {
    c1: Tensor<5>,
    c2: Tensor<5>,
    c3: Tensor<5>,
    c4: Tensor<5>,
}

impl CostCompute {
    /// Builds the cost network for `CH = channels` and `num_cameras` spherical features.
    pub fn new(channels: usize, num_cameras: usize, device: &Device) -> Self {
        let ch = 2 * channels;
        let conv = |cin: usize, cout: usize, stride: usize| {
            ConvBn3d::new([cin, cout], 3, stride, 1, true, true, device)
        };
        let mut convs = vec![conv(ch, ch, 1), conv(ch, ch, 1), conv(ch, ch, 1)];
        for (cin, cout) in [
            (ch, 2 * ch),
            (2 * ch, 2 * ch),
            (2 * ch, 2 * ch),
            (2 * ch, 4 * ch),
        ] {
            convs.push(conv(cin, cout, 2));
            convs.push(conv(cout, cout, 1));
            convs.push(conv(cout, cout, 1));
        }
        let deconv = |cin: usize, cout: usize, bn_relu: bool| {
            DeconvBn3d::new([cin, cout], 3, 2, 1, 1, bn_relu, bn_relu, device)
        };
        Self {
            fusion: conv(num_cameras * channels, ch, 1),
            convs,
            deconv1: deconv(4 * ch, 2 * ch, true),
            deconv2: deconv(2 * ch, 2 * ch, true),
            deconv3: deconv(2 * ch, 2 * ch, true),
            deconv4: deconv(2 * ch, ch, true),
            deconv5: deconv(ch, 1, false),
        }
    }

    /// `[B, cams * CH, N/2, H/2, W/2]` concatenated spherical features ->
    /// `[B, 1, N, H, W]` cost.
    pub fn forward(&self, features: Tensor<5>) -> Tensor<5> {
        let fused = self.fusion.forward(features, None); // [B, 2CH, N/2, H/2, W/2]
        self.regularize(fused)
    }

    /// The fusion convolution (bias included, before batch norm and ReLU) computed one camera
    /// at a time: `sum_j conv(S_j, W[:, slot j])`, the same as the convolution of the
    /// concatenation but without holding all cameras' features at once. `next(slot)` returns the spherical feature `[B, CH, N/2, H/2, W/2]` of the
    /// camera placed at `slot` of the concatenation; it is dropped as soon as it is used.
    /// `num_slots` must be the number of cameras the network was built for.
    pub fn fuse_incrementally(
        &self,
        num_slots: usize,
        mut next: impl FnMut(usize) -> Tensor<5>,
    ) -> Tensor<5> {
        let weight = self.fusion.conv.weight.val(); // [2CH, cams*CH, 3, 3, 3]
        let [_, in_channels, _, _, _] = weight.dims();
        let per_slot = in_channels / num_slots.max(1);
        let conv = &self.fusion.conv;
        let options = ConvOptions::new(conv.stride, [FUSION_PAD; 3], conv.dilation, conv.groups);
        let mut part = |slot: usize, bias: Option<Tensor<1>>| {
            let feature = next(slot); // [B, CH, N/2, H/2, W/2]
            let w = weight.clone().narrow(1, slot * per_slot, per_slot); // [2CH, CH, 3, 3, 3]
            conv3d(feature, w, bias, options.clone()) // [B, 2CH, N/2, H/2, W/2]
        };
        let mut fused = part(0, conv.bias.as_ref().map(|b| b.val()));
        for slot in 1..num_slots {
            fused = fused + part(slot, None);
        }
        fused // [B, 2CH, N/2, H/2, W/2]
    }

    /// Its 3D convolutions (3Dconv1-15) also on the host ([`ConvBn3d::with_host_conv`]);
    /// the fusion and the transposed convolutions keep burn's.
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            convs: self
                .convs
                .into_iter()
                .map(ConvBn3d::with_host_conv)
                .collect(),
            ..self
        }
    }

    /// Encoder-decoder from the fused volume `[B, 2CH, N/2, H/2, W/2]` to `[B, 1, N, H, W]`.
    pub fn regularize(&self, fused: Tensor<5>) -> Tensor<5> {
        let (bottom, skips) = self.encode(fused);
        self.decode(bottom, skips)
    }

    fn encode(&self, fused: Tensor<5>) -> (Tensor<5>, Skips) {
        let c = self.convs[0].forward(fused, None); // [B, 2CH, N/2, H/2, W/2]
        let c1 = self.convs[1].forward(c.clone(), None);
        let c1 = self.convs[2].forward(c1, None); // [B, 2CH, N/2, H/2, W/2]
        let c = self.convs[3].forward(c, None); // [B, 4CH, N/4, H/4, W/4]
        let c2 = self.convs[4].forward(c.clone(), None);
        let c2 = self.convs[5].forward(c2, None); // [B, 4CH, N/4, H/4, W/4]
        let c = self.convs[6].forward(c, None); // [B, 4CH, N/8, H/8, W/8]
        let c3 = self.convs[7].forward(c.clone(), None);
        let c3 = self.convs[8].forward(c3, None); // [B, 4CH, N/8, H/8, W/8]
        let c = self.convs[9].forward(c, None); // [B, 4CH, N/16, H/16, W/16]
        let c4 = self.convs[10].forward(c.clone(), None);
        let c4 = self.convs[11].forward(c4, None); // [B, 4CH, N/16, H/16, W/16]
        let c = self.convs[12].forward(c, None); // [B, 8CH, N/32, H/32, W/32]
        let c5 = self.convs[13].forward(c, None);
        let c5 = self.convs[14].forward(c5, None); // [B, 8CH, N/32, H/32, W/32]
        (c5, Skips { c1, c2, c3, c4 })
    }

    fn decode(&self, c5: Tensor<5>, skips: Skips) -> Tensor<5> {
        let c = self.deconv1.forward(c5, Some(skips.c4)); // [B, 4CH, N/16, H/16, W/16]
        let c = self.deconv2.forward(c, Some(skips.c3)); // [B, 4CH, N/8, H/8, W/8]
        let c = self.deconv3.forward(c, Some(skips.c2)); // [B, 4CH, N/4, H/4, W/4]
        let c = self.deconv4.forward(c, Some(skips.c1)); // [B, 2CH, N/2, H/2, W/2]
        self.deconv5.forward(c, None) // [B, 1, N, H, W]
    }

    /// Folds the batch norms into the convolutions (inference only).
    pub fn fold_batch_norm(self) -> Self {
        Self {
            fusion: self.fusion.fold_batch_norm(),
            convs: self
                .convs
                .into_iter()
                .map(ConvBn3d::fold_batch_norm)
                .collect(),
            deconv1: self.deconv1.fold_batch_norm(),
            deconv2: self.deconv2.fold_batch_norm(),
            deconv3: self.deconv3.fold_batch_norm(),
            deconv4: self.deconv4.fold_batch_norm(),
            deconv5: self.deconv5.fold_batch_norm(),
        }
    }
}
