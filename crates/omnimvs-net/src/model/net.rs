//! The whole network: features per camera, sweep, fusion, cost regularisation, softargmin.

use std::time::Instant;

use burn::module::{Module, Param};
use burn::tensor::{Device, Tensor};

use super::cost::CostCompute;
use super::feature::FeatureLayers;
use super::softargmin::{entropy, expected_index, probability};
use super::sweep::{SphericalSweep, SweepTaps};
use crate::config::NetConfig;
use crate::error::NetError;
use crate::taps::SweepGrid;

/// Gray input images: one channel.
pub const INPUT_CHANNELS: usize = 1;

/// Spheres warped and transferred at a time in the sweep; bounds the memory of the warped
/// features (`chunk * CH * H * W` floats).
pub const DEFAULT_SWEEP_CHUNK: usize = 8;

/// OmniMVS: `feature_layers`, `spherical_sweep` and `cost_computes` named like the reference
/// PyTorch module so that its state dicts load directly.
#[derive(Module, Debug)]
pub struct OmniMvsNet {
    /// Unary feature extraction, shared by all cameras.
    pub feature_layers: FeatureLayers,
    /// Transference convolution of the sweep.
    pub spherical_sweep: SphericalSweep,
    /// Fusion and 3D encoder-decoder.
    pub cost_computes: CostCompute,
    /// The sizes the network was built for.
    #[module(skip)]
    pub config: NetConfig,
}

/// Wall time of each inference stage in seconds. The fusion convolution runs camera by camera
/// inside the sweep loop and is counted outside `features` and `sweep`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimings {
    /// Unary features of all cameras.
    pub features: f64,
    /// Warp and transference of all cameras.
    pub sweep: f64,
    /// Per-camera fusion convolutions (the remainder of the fusion loop).
    pub fusion: f64,
    /// Batch norm and ReLU of the fusion.
    pub fusion_finish: f64,
    /// 3D encoder-decoder.
    pub cost: f64,
    /// Softmax, softargmin.
    pub softargmin: f64,
    /// Whole forward pass.
    pub total: f64,
}

/// Waits for a tensor's computation when `timed` (backends may be asynchronous: a stage's
/// time is only known once its work is done).
fn wait<const D: usize>(tensor: &Tensor<D>, timed: bool) {
    if !timed {
        return;
    }
    // Errors surface again when the tensor is read.
    let _ = tensor.device().sync();
}

/// Where the inference sweep runs: the lookup tables of every camera for the host kernel, or
/// their taps already on the device.
#[derive(Clone, Copy, Debug)]
pub enum SweepInput<'a> {
    /// Host warp kernel (skips invalid samples; best on CPU backends).
    Host(&'a [SweepGrid]),
    /// Gather on the device (GPU backends).
    Device(&'a [SweepTaps]),
}

impl SweepInput<'_> {
    fn len(&self) -> usize {
        match self {
            SweepInput::Host(grids) => grids.len(),
            SweepInput::Device(taps) => taps.len(),
        }
    }
}

/// Outputs of a forward pass.
#[derive(Clone, Debug)]
pub struct NetOutput {
    /// Regularised cost volume `[B, N, H, W]` (softmax input).
    pub cost: Tensor<4>,
    /// Per-pixel distribution over the hypotheses `[B, N, H, W]`.
    pub prob: Tensor<4>,
    /// Softargmin inverse-depth index `[B, H, W]`, in `[0, N - 1]`.
    pub index: Tensor<3>,
}

impl NetOutput {
    /// Entropy of the per-pixel distribution `[B, H, W]` (nats).
    pub fn entropy(&self) -> Tensor<3> {
        entropy(self.prob.clone())
    }
}

impl OmniMvsNet {
    /// Builds a randomly initialised network.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when `config` fails [`NetConfig::validate`].
    pub fn new(config: &NetConfig, device: &Device) -> Result<Self, NetError> {
        if config.family != crate::config::Family::OmniMvs {
            return Err(NetError::InvalidConfig {
                field: "family",
                message: format!(
                    "expected the paper's network (`omni_mvs`), got {:?}: build it with \
                     CascadeNet::new",
                    config.family
                ),
            });
        }
        config.validate()?;
        Ok(Self {
            feature_layers: FeatureLayers::new(
                INPUT_CHANNELS,
                config.channels,
                config.layout,
                device,
            ),
            spherical_sweep: SphericalSweep::new(config.channels, device),
            cost_computes: CostCompute::new(config.channels, config.num_cameras, device),
            config: config.clone(),
        })
    }

    /// Checks a camera order: a permutation of `0..num_cameras`; `slot j` of the
    /// concatenation receives camera `order[j]`.
    ///
    /// # Errors
    /// [`NetError::CameraOrder`] otherwise.
    pub fn check_order(&self, order: &[usize]) -> Result<(), NetError> {
        let n = self.config.num_cameras;
        let mut seen = vec![false; n];
        let ok = order.len() == n
            && order
                .iter()
                .all(|&c| c < n && !std::mem::replace(&mut seen[c], true));
        if ok {
            Ok(())
        } else {
            Err(NetError::CameraOrder {
                order: order.to_vec(),
                num_cameras: n,
            })
        }
    }

    /// Identity camera order `0, 1, ..., num_cameras - 1`.
    pub fn identity_order(&self) -> Vec<usize> {
        (0..self.config.num_cameras).collect()
    }

    /// Unary features of one camera: `[B, 1, H_I, W_I] -> [B, CH, H_I/2, W_I/2]`.
    pub fn features(&self, image: Tensor<4>) -> Tensor<4> {
        self.feature_layers.forward(image)
    }

    /// Cost volume `[B, 1, N, H, W]` from the per-camera spherical features
    /// `[B, CH, N/2, H/2, W/2]`, concatenated in `order`.
    pub fn cost_volume(&self, spherical: Vec<Tensor<5>>, order: &[usize]) -> Tensor<5> {
        let mut slots: Vec<Option<Tensor<5>>> = spherical.into_iter().map(Some).collect();
        let ordered: Vec<Tensor<5>> = order.iter().filter_map(|&c| slots[c].take()).collect();
        let concat = Tensor::cat(ordered, 1); // [B, cams*CH, N/2, H/2, W/2]
        self.cost_computes.forward(concat) // [B, 1, N, H, W]
    }

    /// Differentiable forward pass (training and parity): `images[i]` `[B, 1, H_I, W_I]` and
    /// `taps[i]` belong to camera `i`; `order` is the concatenation order.
    ///
    /// # Errors
    /// [`NetError::CameraOrder`] or [`NetError::Shape`] for inconsistent inputs.
    pub fn forward(
        &self,
        images: &[Tensor<4>],
        taps: &[SweepTaps],
        order: &[usize],
    ) -> Result<NetOutput, NetError> {
        self.check_order(order)?;
        self.check_inputs(images.len(), taps.len())?;
        let spherical: Vec<Tensor<5>> = images
            .iter()
            .zip(taps)
            .map(|(image, taps)| {
                let feature = self.features(image.clone()); // [B, CH, H_I/2, W_I/2]
                self.spherical_sweep
                    .forward(feature, taps, DEFAULT_SWEEP_CHUNK) // [B, CH, N/2, H/2, W/2]
            })
            .collect();
        let cost = self.cost_volume(spherical, order); // [B, 1, N, H, W]
        Ok(Self::softargmin(cost))
    }

    /// Memory-lean inference (batch 1, no gradient): camera by camera, features, host sweep
    /// and the fusion's share of that camera, so that only one camera's intermediates live at
    /// a time. `images[i]` is `[1, 1, H_I, W_I]`, `grids[i]` camera `i`'s lookup table.
    ///
    /// # Errors
    /// [`NetError::CameraOrder`] or [`NetError::Shape`] for inconsistent inputs.
    pub fn infer(
        &self,
        images: &[Tensor<4>],
        grids: &[SweepGrid],
        order: &[usize],
    ) -> Result<NetOutput, NetError> {
        self.infer_timed(images, grids, order).map(|(out, _)| out)
    }

    /// [`OmniMvsNet::infer`] that also measures the wall time of each stage.
    ///
    /// # Errors
    /// See [`OmniMvsNet::infer`].
    pub fn infer_timed(
        &self,
        images: &[Tensor<4>],
        grids: &[SweepGrid],
        order: &[usize],
    ) -> Result<(NetOutput, StageTimings), NetError> {
        self.infer_timed_with(images, SweepInput::Host(grids), order)
    }

    /// Memory-lean inference with the sweep of `sweep`: the host kernel (CPU backends) or the
    /// device taps (GPU backends, where a round trip through host memory would dominate).
    ///
    /// # Errors
    /// See [`OmniMvsNet::infer`].
    pub fn infer_timed_with(
        &self,
        images: &[Tensor<4>],
        sweep: SweepInput<'_>,
        order: &[usize],
    ) -> Result<(NetOutput, StageTimings), NetError> {
        self.infer_with(images, sweep, order, true)
    }

    /// [`OmniMvsNet::infer_timed_with`] that waits for the device after each stage, and so
    /// measures the stages, only when `timed` (otherwise only `total` is set, the time to
    /// queue the work on an asynchronous backend).
    ///
    /// # Errors
    /// See [`OmniMvsNet::infer`].
    pub fn infer_with(
        &self,
        images: &[Tensor<4>],
        sweep: SweepInput<'_>,
        order: &[usize],
        timed: bool,
    ) -> Result<(NetOutput, StageTimings), NetError> {
        self.check_order(order)?;
        self.check_inputs(images.len(), sweep.len())?;
        let mut timings = StageTimings::default();
        let mut failure = None;
        let total = Instant::now();
        let cost = {
            let fused = self.cost_computes.fuse_incrementally(order.len(), |slot| {
                let camera = order[slot];
                let start = Instant::now();
                let feature = self.features(images[camera].clone()); // [1, CH, H_I/2, W_I/2]
                wait(&feature, timed);
                timings.features += start.elapsed().as_secs_f64();
                let start = Instant::now();
                let spherical = match sweep {
                    SweepInput::Host(grids) => self.spherical_sweep.forward_host(
                        feature,
                        &grids[camera],
                        DEFAULT_SWEEP_CHUNK,
                    ),
                    SweepInput::Device(taps) => Ok(self.spherical_sweep.forward(
                        feature,
                        &taps[camera],
                        DEFAULT_SWEEP_CHUNK,
                    )),
                }; // [1, CH, N/2, H/2, W/2]
                let spherical = match spherical {
                    Ok(spherical) => spherical,
                    Err(e) => {
                        failure = Some(e);
                        Tensor::zeros(self.spherical_dims(), &images[camera].device())
                    }
                };
                wait(&spherical, timed);
                timings.sweep += start.elapsed().as_secs_f64();
                spherical
            });
            wait(&fused, timed);
            timings.fusion = total.elapsed().as_secs_f64() - timings.features - timings.sweep;
            let start = Instant::now();
            let fused = self.cost_computes.fusion.finish(fused, None); // [1, 2CH, N/2, H/2, W/2]
            wait(&fused, timed);
            timings.fusion_finish = start.elapsed().as_secs_f64();
            let start = Instant::now();
            let cost = self.cost_computes.regularize(fused); // [1, 1, N, H, W]
            wait(&cost, timed);
            timings.cost = start.elapsed().as_secs_f64();
            cost
        };
        if let Some(e) = failure {
            return Err(e);
        }
        let start = Instant::now();
        let out = Self::softargmin(cost);
        wait(&out.index, timed);
        timings.softargmin = start.elapsed().as_secs_f64();
        timings.total = total.elapsed().as_secs_f64();
        Ok((out, timings))
    }

    /// `[B, CH, N/2, H/2, W/2]` for batch 1.
    fn spherical_dims(&self) -> [usize; 5] {
        let c = &self.config;
        [
            1,
            c.channels,
            c.num_spheres(),
            c.out_height / 2,
            c.out_width / 2,
        ]
    }

    fn check_inputs(&self, images: usize, grids: usize) -> Result<(), NetError> {
        let cams = self.config.num_cameras;
        if images != cams || grids != cams {
            return Err(NetError::Shape {
                what: "images and lookup tables per camera".into(),
                expected: vec![cams, cams],
                actual: vec![images, grids],
            });
        }
        Ok(())
    }

    /// Softargmin of a `[B, 1, N, H, W]` cost volume.
    pub fn softargmin(cost: Tensor<5>) -> NetOutput {
        let cost = cost.squeeze_dim::<4>(1); // [B, N, H, W]
        let prob = probability(cost.clone()); // [B, N, H, W]
        let index = expected_index(prob.clone()); // [B, H, W]
        NetOutput { cost, prob, index }
    }

    /// Folds every batch norm into its convolution: same outputs in inference, fewer passes
    /// over the volumes. The result cannot be trained or saved in the reference layout.
    pub fn fold_batch_norm(self) -> Self {
        Self {
            feature_layers: self.feature_layers.fold_batch_norm(),
            spherical_sweep: self.spherical_sweep,
            cost_computes: self.cost_computes.fold_batch_norm(),
            config: self.config,
        }
    }

    /// The network with its convolutions (features, transference, 3Dconv1-15) also on the
    /// host ([`crate::hostconv`]), which its forward pass uses from then on: for inference on
    /// burn flex, after [`OmniMvsNet::fold_batch_norm`]. The fusion and the transposed
    /// convolutions keep burn's.
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            feature_layers: self.feature_layers.with_host_convs(),
            spherical_sweep: self.spherical_sweep.with_host_convs(),
            cost_computes: self.cost_computes.with_host_convs(),
            config: self.config,
        }
    }

    /// Multiplies the final cost (3Ddeconv5's weights and bias) by `factor`, the inverse of a
    /// softmax temperature. A randomly initialised network has nearly equal costs, so its
    /// softargmin is almost flat and hides kernel differences; a sharpened one makes a
    /// full-size parity check between backends sensitive (`omnimvs parity --cost-scale`).
    pub fn scale_cost(mut self, factor: f32) -> Self {
        let conv = &mut self.cost_computes.deconv5.conv;
        conv.weight = Param::from_tensor(conv.weight.val().mul_scalar(factor));
        if let Some(bias) = conv.bias.take() {
            conv.bias = Some(Param::from_tensor(bias.val().mul_scalar(factor)));
        }
        self
    }
}
