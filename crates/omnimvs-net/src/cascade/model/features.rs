//! The cascade's feature pyramid: strides 2, 4 and 8 of every fisheye image, shared by all
//! cameras, and its widening at stride 8 for a trained network.

use burn::module::Module;
use burn::module::Param;
use burn::tensor::{Device, Tensor};

use crate::error::NetError;
use crate::model::blocks::ConvBn2d;

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
    pub(super) fn new(channels: [usize; 3], context_pairs: usize, device: &Device) -> Self {
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
        wrap_cols: old.wrap_cols,
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
        wrap_cols: old.wrap_cols,
        host: None,
    }
}
