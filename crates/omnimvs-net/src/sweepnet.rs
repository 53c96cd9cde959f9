//! The SweepNet-style matching-cost network (Won et al., ICRA 2019), sized for a
//! CPU: the learned head of `omnimvs_stereo::sweepnet`, a small perceptron that reads the
//! window features of the warped images of every camera at a sphere point (each pair's ZNCC,
//! each window's texture, which windows are complete) and gives the point's matching cost in
//! `[0, 1]`, regularised by the same SGM as ZNCC.
//!
//! Trained here with burn (`omnimvs train --cost sweepnet`); run by `omnimvs-stereo` as a
//! plain [`Mlp`] ([`SweepNet::head`]), so that inference needs no tensor library.

use std::path::Path;
use std::sync::Arc;

use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Tensor, activation};
use omnimvs_stereo::sweepnet::{Dense, FeatureLayout, FeatureSpec, SweepCostHead};
use omnimvs_stereo::{LearnedCost, Mlp};
use serde::{Deserialize, Serialize};

use crate::error::NetError;

/// Sizes of the network and the SGM penalties it was tuned with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepNetConfig {
    /// `"sweepnet"`.
    pub family: String,
    /// Cameras of the rig it reads (the feature length follows: 20 for four).
    pub cameras: usize,
    /// Widths of the hidden layers.
    pub hidden: Vec<usize>,
    /// Half sides of the windows on the warped images, first one first (4: 9x9); the first
    /// also normalises the centre samples.
    pub radii: Vec<usize>,
    /// Also the shifted-window features (`omnimvs_stereo::sweepnet::FeatureSpec::shifted`).
    #[serde(default)]
    pub shifted: bool,
    /// Sharpness of the softmin over the hypotheses in the training loss.
    pub temperature: f32,
    /// SGM `P1` for this cost (matching-cost units).
    pub p1: f32,
    /// SGM `P2` for this cost.
    pub p2: f32,
    /// Share of the plain 9x9 ZNCC cost in the cost SGM gets, `(1 - w) * learned + w * zncc`
    /// (`omnimvs_stereo::SweepCostHead::zncc_weight`; 0, the default: the learned cost alone).
    #[serde(default)]
    pub zncc_weight: f32,
}

impl Default for SweepNetConfig {
    fn default() -> Self {
        Self {
            family: "sweepnet".into(),
            cameras: 4,
            hidden: vec![32, 16],
            radii: vec![4, 2, 7],
            shifted: true,
            temperature: 10.0,
            p1: omnimvs_stereo::DEFAULT_P1,
            p2: omnimvs_stereo::DEFAULT_P2,
            zncc_weight: 0.0,
        }
    }
}

impl SweepNetConfig {
    /// Features per sphere point.
    pub fn inputs(&self) -> usize {
        self.layout().dim()
    }

    /// Which window features it reads.
    pub fn spec(&self) -> FeatureSpec {
        FeatureSpec {
            radii: self.radii.clone(),
            shifted: self.shifted,
        }
    }

    /// Where each feature sits.
    pub fn layout(&self) -> FeatureLayout {
        self.spec().layout(self.cameras)
    }

    /// Multiply-accumulates per sphere point.
    pub fn macs_per_point(&self) -> usize {
        self.widths().windows(2).map(|w| w[0] * w[1]).sum()
    }

    /// Widths of the layers from the input to the one output.
    pub fn widths(&self) -> Vec<usize> {
        let mut widths = vec![self.inputs()];
        widths.extend(&self.hidden);
        widths.push(1);
        widths
    }

    fn validate(&self) -> Result<(), NetError> {
        let bad = |field, message: &str| NetError::InvalidConfig {
            field,
            message: message.into(),
        };
        if self.family != "sweepnet" {
            return Err(bad("family", "expected \"sweepnet\""));
        }
        if self.cameras < 2 {
            return Err(bad("cameras", "expected at least two cameras"));
        }
        if self.radii.is_empty() || self.radii.contains(&0) {
            return Err(bad(
                "radii",
                "expected at least one window half side, each >= 1",
            ));
        }
        if !(0.0..=1.0).contains(&self.zncc_weight) {
            return Err(bad("zncc_weight", "expected a share in [0, 1]"));
        }
        if self.hidden.contains(&0) {
            return Err(bad("hidden", "expected layers of at least one unit"));
        }
        if !(self.temperature.is_finite() && self.temperature > 0.0) {
            return Err(bad("temperature", "expected a positive number"));
        }
        Ok(())
    }
}

/// The perceptron.
#[derive(Module, Debug)]
pub struct SweepNet {
    pub layers: Vec<Linear>,
    #[module(skip)]
    pub config: SweepNetConfig,
}

impl SweepNet {
    /// The method's name in reports.
    pub const NAME: &'static str = "SweepNet+SGM";

    /// A network of random weights on `device`.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`].
    pub fn new(config: &SweepNetConfig, device: &Device) -> Result<Self, NetError> {
        config.validate()?;
        let layers = config
            .widths()
            .windows(2)
            .map(|w| LinearConfig::new(w[0], w[1]).init(device))
            .collect();
        Ok(Self {
            layers,
            config: config.clone(),
        })
    }

    /// `[B, features]` -> `[B]` costs before the sigmoid.
    pub fn logits(&self, x: Tensor<2>) -> Tensor<1> {
        let last = self.layers.len() - 1;
        let mut x = x;
        for (k, l) in self.layers.iter().enumerate() {
            x = l.forward(x);
            if k < last {
                x = activation::relu(x);
            }
        }
        x.flatten(0, 1)
    }

    /// `[B, features]` -> `[B]` costs in `[0, 1]`.
    pub fn costs(&self, x: Tensor<2>) -> Tensor<1> {
        activation::sigmoid(self.logits(x))
    }

    /// The weights as the plain perceptron `omnimvs-stereo` runs.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] if a tensor cannot be read back (a backend defect).
    pub fn head(&self) -> Result<Mlp, NetError> {
        let read = |t: Tensor<2>| {
            t.into_data()
                .try_into_vec::<f32>()
                .map_err(|e| NetError::InvalidConfig {
                    field: "layers",
                    message: format!("{e:?}"),
                })
        };
        let mut layers = Vec::with_capacity(self.layers.len());
        for l in &self.layers {
            // burn stores `[inputs, outputs]`; the perceptron wants `[outputs][inputs]`.
            let w = l.weight.val();
            let [inputs, outputs] = w.dims();
            let weight = read(w.transpose())?;
            let bias = match &l.bias {
                Some(b) => read(b.val().unsqueeze::<2>())?,
                None => vec![0.0; outputs],
            };
            layers.push(Dense {
                inputs,
                outputs,
                weight,
                bias,
            });
        }
        Mlp::new(Self::NAME, self.config.spec(), layers)
            .and_then(|m| m.with_zncc_weight(self.config.zncc_weight))
            .map_err(|e| NetError::InvalidConfig {
                field: "layers",
                message: e.to_string(),
            })
    }

    /// The network as the learned cost of `omnimvs_stereo`'s SGM.
    ///
    /// # Errors
    /// As [`Self::head`].
    pub fn learned_cost(&self) -> Result<LearnedCost, NetError> {
        let head: Arc<dyn SweepCostHead> = Arc::new(self.head()?);
        Ok(LearnedCost::Sweep(head))
    }
}

/// The bundled network's configuration (`models/sweepnet.json`).
pub const BUNDLED_CONFIG: &str = include_str!("../../../models/sweepnet.json");
/// The bundled network's weights (`models/sweepnet.safetensors`).
pub const BUNDLED_WEIGHTS: &[u8] = include_bytes!("../../../models/sweepnet.safetensors");

/// Writes the weights (safetensors) and the configuration beside them (`.json`).
///
/// # Errors
/// [`NetError`] when a file cannot be written.
pub fn save(net: &SweepNet, path: &Path) -> Result<(), NetError> {
    crate::weights::save_with_config(net, &net.config, path)
}

/// A network saved by [`save`].
///
/// # Errors
/// [`NetError`] when a file is missing or does not fit.
pub fn load(path: &Path, device: &Device) -> Result<SweepNet, NetError> {
    let config: SweepNetConfig = crate::weights::read_json(&crate::weights::config_path(path))?;
    crate::weights::apply_file(SweepNet::new(&config, device)?, path)
}

/// The bundled network (`models/sweepnet.*`).
///
/// # Errors
/// [`NetError`] if the compiled-in files do not fit (a build defect).
pub fn bundled(device: &Device) -> Result<SweepNet, NetError> {
    let name = Path::new("models/sweepnet.safetensors");
    let config: SweepNetConfig = crate::weights::parse_config(name, BUNDLED_CONFIG)?;
    crate::weights::apply_bytes(SweepNet::new(&config, device)?, name, BUNDLED_WEIGHTS)
}

/// `bundled`, `random` (seeded weights, for tests) or a `.safetensors` file.
///
/// # Errors
/// As [`load`].
pub fn from_name(name: &str, device: &Device) -> Result<SweepNet, NetError> {
    match name {
        "bundled" | "sweepnet" => bundled(device),
        "random" => SweepNet::new(&SweepNetConfig::default(), device),
        path => load(Path::new(path), device),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::Distribution;

    #[test]
    fn the_plain_head_computes_what_burn_computes() {
        let device = Device::flex();
        let net = SweepNet::new(&SweepNetConfig::default(), &device).unwrap();
        let dim = SweepNetConfig::default().inputs();
        let x = Tensor::<2>::random([7, dim], Distribution::Normal(0.0, 1.0), &device);
        let want = net
            .costs(x.clone())
            .into_data()
            .try_into_vec::<f32>()
            .unwrap();
        let features = x.into_data().try_into_vec::<f32>().unwrap();
        let mut got = vec![0f32; 7];
        net.head().unwrap().costs(&features, &mut got);
        for (a, b) in want.iter().zip(&got) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
        assert_eq!(
            SweepNetConfig::default().macs_per_point(),
            dim * 32 + 32 * 16 + 16
        );
    }

    #[test]
    fn bundled_weights_load_and_bad_configs_are_refused() {
        let net = bundled(&Device::flex()).unwrap();
        assert_eq!(net.config.family, "sweepnet");
        let bad = SweepNetConfig {
            hidden: vec![0],
            ..SweepNetConfig::default()
        };
        assert!(SweepNet::new(&bad, &Device::flex()).is_err());
    }
}
