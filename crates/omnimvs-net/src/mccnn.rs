//! The MC-CNN-fast style matching-cost network (Zbontar and LeCun, JMLR 2016, section 3.2):
//! a siamese tower of `layers` 3x3 convolutions (ReLU between them, none after the
//! last) whose output at a pixel describes the 9x9 patch around it; two patches match when
//! the cosine similarity of their descriptors is high.
//!
//! Our choice for a fisheye rig: the tower runs once per frame on each camera's fisheye image
//! (downscaled by [`McCnnConfig::stride`], normalised like every network input), and the
//! descriptors are sampled where each sphere point projects ([`omnimvs_stereo::learned`]),
//! instead of running the tower on the warped patch of every sphere (what the OmniMVS paper
//! did with ZNCC's 9x9 spherical patches): `N` times less work, at the price of comparing
//! patches that the fisheye distorts differently in each camera, which the training patches
//! (drawn through the real rig) teach the network to tolerate.

use std::path::Path;
use std::sync::Arc;

use burn::module::Module;
use burn::nn::PaddingConfig2d;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::tensor::{Device, Tensor, TensorData, activation};
use omnimvs_camera::ValidityMask;
use omnimvs_core::GrayImage;
use omnimvs_data::image_io::normalize_for_network;
use omnimvs_stereo::{FeatureExtractor, FeatureMap, StereoError};
use serde::{Deserialize, Serialize};

use crate::error::NetError;

/// Sizes of the matching-cost network and the SGM penalties it was tuned with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct McCnnConfig {
    /// `"mccnn"`.
    pub family: String,
    /// Number of 3x3 convolutions (4 in MC-CNN-fast: a 9x9 patch).
    pub layers: usize,
    /// Channels of the hidden layers (64 in MC-CNN-fast).
    pub hidden: usize,
    /// Channels of the descriptor.
    pub features: usize,
    /// Fisheye pixels per descriptor pixel (images are averaged over `stride x stride`
    /// blocks first).
    pub stride: usize,
    /// SGM `P1` for this cost (matching-cost units).
    pub p1: f32,
    /// SGM `P2` for this cost.
    pub p2: f32,
}

impl Default for McCnnConfig {
    fn default() -> Self {
        Self {
            family: "mccnn".into(),
            layers: 4,
            hidden: 32,
            features: 16,
            stride: 2,
            p1: omnimvs_stereo::DEFAULT_P1,
            p2: omnimvs_stereo::DEFAULT_P2,
        }
    }
}

impl McCnnConfig {
    /// Side of the patch one descriptor sees, in stride pixels: `2 layers + 1`.
    pub fn patch(&self) -> usize {
        2 * self.layers + 1
    }

    /// Multiply-accumulates per descriptor pixel.
    pub fn macs_per_pixel(&self) -> usize {
        (0..self.layers)
            .map(|l| {
                let cin = if l == 0 { 1 } else { self.hidden };
                let cout = if l + 1 == self.layers {
                    self.features
                } else {
                    self.hidden
                };
                9 * cin * cout
            })
            .sum()
    }

    fn validate(&self) -> Result<(), NetError> {
        let bad = |field, message: &str| NetError::InvalidConfig {
            field,
            message: message.into(),
        };
        if self.family != "mccnn" {
            return Err(bad("family", "expected \"mccnn\""));
        }
        if self.layers < 1 || self.hidden < 1 || self.features < 1 {
            return Err(bad("layers", "expected at least one layer and channel"));
        }
        if self.stride < 1 {
            return Err(bad("stride", "expected at least 1"));
        }
        Ok(())
    }
}

/// The siamese tower.
#[derive(Module, Debug)]
pub struct McCnn {
    /// 3x3 convolutions without padding.
    pub convs: Vec<Conv2d>,
    #[module(skip)]
    pub config: McCnnConfig,
}

impl McCnn {
    /// A network of random weights on `device`.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`].
    pub fn new(config: &McCnnConfig, device: &Device) -> Result<Self, NetError> {
        config.validate()?;
        let convs = (0..config.layers)
            .map(|l| {
                let cin = if l == 0 { 1 } else { config.hidden };
                let cout = if l + 1 == config.layers {
                    config.features
                } else {
                    config.hidden
                };
                Conv2dConfig::new([cin, cout], [3, 3])
                    .with_padding(PaddingConfig2d::Valid)
                    .init(device)
            })
            .collect();
        Ok(Self {
            convs,
            config: config.clone(),
        })
    }

    /// `[B, 1, H, W]` -> `[B, F, H - 2 layers, W - 2 layers]`, not normalised.
    pub fn forward(&self, x: Tensor<4>) -> Tensor<4> {
        let last = self.convs.len() - 1;
        let mut x = x;
        for (l, conv) in self.convs.iter().enumerate() {
            x = conv.forward(x);
            if l < last {
                x = activation::relu(x);
            }
        }
        x
    }

    /// Unit descriptors `[B, F]` of `patch x patch` patches `[B, 1, patch, patch]`.
    pub fn describe(&self, patches: Tensor<4>) -> Tensor<2> {
        let [b, ..] = patches.dims();
        let f = self.forward(patches).reshape([b as i32, -1]);
        let norm = f.clone().powi_scalar(2).sum_dim(1).add_scalar(1e-12).sqrt();
        f / norm
    }

    /// The network input of one camera: normalised over the valid pixels, averaged over
    /// `stride` blocks, edges repeated by `layers` pixels so that the output has the pooled
    /// size. Returns the padded rows and the pooled `(width, height)`.
    ///
    /// # Errors
    /// [`NetError::Data`] for a mask of another size.
    pub fn prepare(
        &self,
        image: &GrayImage,
        mask: Option<&ValidityMask>,
    ) -> Result<(Vec<f32>, usize, usize), NetError> {
        let norm = normalize_for_network(image, mask)?;
        let pooled = pool(&norm, self.config.stride);
        let pad = self.config.layers;
        let (w, h) = (pooled.width, pooled.height);
        let (pw, ph) = (w + 2 * pad, h + 2 * pad);
        let mut out = vec![0f32; pw * ph];
        for y in 0..ph {
            let sy = y.saturating_sub(pad).min(h - 1);
            for x in 0..pw {
                let sx = x.saturating_sub(pad).min(w - 1);
                out[y * pw + x] = pooled.data[sy * w + sx];
            }
        }
        Ok((out, w, h))
    }
}

/// The mean of `stride x stride` blocks (the last partial blocks dropped).
pub fn pool(image: &GrayImage, stride: usize) -> GrayImage {
    if stride == 1 {
        return image.clone();
    }
    let (w, h) = (image.width / stride, image.height / stride);
    let inv = 1.0 / (stride * stride) as f32;
    let mut data = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0f32;
            for dy in 0..stride {
                let row = (y * stride + dy) * image.width + x * stride;
                s += image.data[row..row + stride].iter().sum::<f32>();
            }
            data[y * w + x] = s * inv;
        }
    }
    GrayImage {
        width: w,
        height: h,
        data,
    }
}

/// The network as a [`FeatureExtractor`] for `omnimvs_stereo`'s learned cost: the cameras'
/// masks for the input normalisation and the device it runs on.
#[derive(Debug)]
pub struct McCnnExtractor {
    pub net: McCnn,
    pub masks: Option<Vec<ValidityMask>>,
    pub device: Device,
}

impl McCnnExtractor {
    /// The method's name in reports.
    pub const NAME: &'static str = "MC-CNN+SGM";

    /// Wrapped for `SgmEstimator::with_features`.
    pub fn shared(self) -> Arc<dyn FeatureExtractor> {
        Arc::new(self)
    }

    /// The feature maps of one frame.
    ///
    /// # Errors
    /// [`NetError`] for images and masks of different sizes.
    pub fn feature_maps(&self, images: &[GrayImage]) -> Result<Vec<FeatureMap>, NetError> {
        let mut maps = Vec::with_capacity(images.len());
        for (i, img) in images.iter().enumerate() {
            let mask = self.masks.as_ref().and_then(|m| m.get(i));
            let (input, w, h) = self.net.prepare(img, mask)?;
            let pad = 2 * self.net.config.layers;
            let x = Tensor::<4>::from_data(
                TensorData::new(input, [1, 1, h + pad, w + pad]),
                &self.device,
            );
            let f = self.net.forward(x); // [1, F, h, w]
            let c = self.net.config.features;
            let hwc = f.reshape([c, h * w]).transpose();
            let data =
                hwc.into_data()
                    .try_into_vec::<f32>()
                    .map_err(|e| NetError::InvalidConfig {
                        field: "features",
                        message: format!("{e:?}"),
                    })?;
            maps.push(FeatureMap {
                width: w,
                height: h,
                channels: c,
                stride: self.net.config.stride,
                data,
            });
        }
        Ok(maps)
    }
}

impl FeatureExtractor for McCnnExtractor {
    fn method_name(&self) -> &str {
        Self::NAME
    }

    fn features(&self, images: &[GrayImage]) -> Result<Vec<FeatureMap>, StereoError> {
        self.feature_maps(images)
            .map_err(|e| StereoError::Volume(format!("MC-CNN features: {e}")))
    }
}

/// The bundled matching-cost network's configuration (`models/mccnn.json`).
pub const BUNDLED_CONFIG: &str = include_str!("../../../models/mccnn.json");
/// The bundled matching-cost network's weights (`models/mccnn.safetensors`).
pub const BUNDLED_WEIGHTS: &[u8] = include_bytes!("../../../models/mccnn.safetensors");

/// Writes the weights (safetensors) and the configuration beside them (`.json`).
///
/// # Errors
/// [`NetError`] when a file cannot be written.
pub fn save(net: &McCnn, path: &Path) -> Result<(), NetError> {
    crate::weights::save_with_config(net, &net.config, path)
}

/// A network from its configuration JSON and safetensors bytes (`name` labels errors).
///
/// # Errors
/// [`NetError`] when they do not parse or do not fit each other.
pub fn load_bytes(
    name: &Path,
    config_json: &str,
    safetensors: &[u8],
    device: &Device,
) -> Result<McCnn, NetError> {
    let config: McCnnConfig = crate::weights::parse_config(name, config_json)?;
    crate::weights::apply_bytes(McCnn::new(&config, device)?, name, safetensors)
}

/// A network saved by [`save`].
///
/// # Errors
/// [`NetError`] when a file is missing or does not fit.
pub fn load(path: &Path, device: &Device) -> Result<McCnn, NetError> {
    let config: McCnnConfig = crate::weights::read_json(&crate::weights::config_path(path))?;
    crate::weights::apply_file(McCnn::new(&config, device)?, path)
}

/// The bundled network (`models/mccnn.*`).
///
/// # Errors
/// [`NetError`] if the compiled-in files do not fit (a build defect).
pub fn bundled(device: &Device) -> Result<McCnn, NetError> {
    load_bytes(
        Path::new("models/mccnn.safetensors"),
        BUNDLED_CONFIG,
        BUNDLED_WEIGHTS,
        device,
    )
}

/// `bundled`, `random` (seeded weights, for tests) or a `.safetensors` file.
///
/// # Errors
/// As [`load`].
pub fn from_name(name: &str, device: &Device) -> Result<McCnn, NetError> {
    match name {
        "bundled" | "mccnn" => bundled(device),
        "random" => McCnn::new(&McCnnConfig::default(), device),
        path => load(Path::new(path), device),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_and_unit_descriptors() {
        let device = Device::flex();
        let cfg = McCnnConfig::default();
        let net = McCnn::new(&cfg, &device).unwrap();
        let p = cfg.patch();
        let x = Tensor::<4>::random(
            [3, 1, p, p],
            burn::tensor::Distribution::Normal(0.0, 1.0),
            &device,
        );
        let d = net.describe(x);
        assert_eq!(d.dims(), [3, cfg.features]);
        let norms = d
            .powi_scalar(2)
            .sum_dim(1)
            .into_data()
            .try_into_vec::<f32>()
            .unwrap();
        for n in norms {
            assert!((n - 1.0).abs() < 1e-4);
        }
        // A whole image keeps its pooled size.
        let img = GrayImage {
            width: 40,
            height: 30,
            data: (0..1200).map(|v| (v % 17) as f32).collect(),
        };
        let ex = McCnnExtractor {
            net,
            masks: None,
            device,
        };
        let maps = ex.feature_maps(&[img]).unwrap();
        assert_eq!((maps[0].width, maps[0].height), (20, 15));
        assert_eq!(maps[0].data.len(), 20 * 15 * cfg.features);
        assert_eq!(cfg.macs_per_pixel(), 9 * (32 + 32 * 32 * 2 + 32 * 16));
    }

    #[test]
    fn bundled_weights_load() {
        let net = bundled(&Device::flex()).unwrap();
        assert_eq!(net.config.family, "mccnn");
    }
}
