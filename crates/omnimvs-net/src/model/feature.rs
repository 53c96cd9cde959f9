//! Unary feature extraction (Table 1, conv1 to conv17, plus the published 18th conv).

use burn::module::Module;
use burn::tensor::{Device, Tensor};

use super::blocks::ConvBn2d;
use crate::config::Layout;

/// Dilations of the eight residual pairs after conv1: five plain pairs, then one pair each
/// dilated by 2, 3 and 4.
const PAIR_DILATIONS: [usize; 8] = [1, 1, 1, 1, 1, 2, 3, 4];

/// The 2D CNN applied to every fisheye image with shared weights. State-dict keys are
/// `feature_layers.layers.{i}.conv` / `.bn` like the reference.
#[derive(Module, Debug)]
pub struct FeatureLayers {
    /// conv1 (5x5, stride 2), 16 residual-pair convolutions, and for the published layout a
    /// final plain 3x3 convolution.
    pub layers: Vec<ConvBn2d>,
}

impl FeatureLayers {
    /// Builds the extractor for `in_channels` input channels (1 for gray) and `channels` = CH.
    pub fn new(in_channels: usize, channels: usize, layout: Layout, device: &Device) -> Self {
        let mut layers = vec![ConvBn2d::new(
            [in_channels, channels],
            5,
            2,
            2,
            1,
            true,
            true,
            device,
        )];
        for dilation in PAIR_DILATIONS {
            for _ in 0..2 {
                layers.push(ConvBn2d::new(
                    [channels, channels],
                    3,
                    1,
                    dilation,
                    dilation,
                    true,
                    true,
                    device,
                ));
            }
        }
        if layout == Layout::Published {
            layers.push(ConvBn2d::new(
                [channels, channels],
                3,
                1,
                1,
                1,
                false,
                false,
                device,
            ));
        }
        Self { layers }
    }

    /// `[B, 1, H_I, W_I] -> [B, CH, H_I/2, W_I/2]` (sizes rounded up).
    pub fn forward(&self, image: Tensor<4>) -> Tensor<4> {
        let mut x = self.layers[0].forward(image, None); // [B, CH, H_I/2, W_I/2]
        let pairs = (self.layers.len() - 1) / 2;
        for pair in 0..pairs {
            let inner = self.layers[1 + 2 * pair].forward(x.clone(), None); // [B, CH, h, w]
            x = self.layers[2 + 2 * pair].forward(inner, Some(x)); // [B, CH, h, w]
        }
        if self.layers.len() == 2 + 2 * pairs {
            x = self.layers[1 + 2 * pairs].forward(x, None); // [B, CH, h, w]
        }
        x
    }

    /// The layers also on the host ([`ConvBn2d::with_host_conv`]; after folding).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            layers: self
                .layers
                .into_iter()
                .map(ConvBn2d::with_host_conv)
                .collect(),
        }
    }

    /// Folds the batch norms into the convolutions (inference only).
    pub fn fold_batch_norm(self) -> Self {
        Self {
            layers: self
                .layers
                .into_iter()
                .map(ConvBn2d::fold_batch_norm)
                .collect(),
        }
    }
}
