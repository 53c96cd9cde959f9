//! Network configuration: sizes, layout variant and presets.

use serde::{Deserialize, Serialize};

use crate::error::NetError;

/// Number of stride-2 levels of the 3D encoder below the half-resolution cost volume.
///
/// The transposed convolutions of the decoder restore the encoder's sizes only when the
/// half-resolution volume divides by `2^ENCODER_LEVELS`.
pub const ENCODER_LEVELS: u32 = 4;

/// Which published layout of the unary feature extractor to build.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// Table 1 of the ICCV 2019 paper: conv1 and eight residual pairs (17 convolutions), the
    /// last pair's ReLU output is the feature map.
    Iccv,
    /// The layout of the public PyTorch weights: the ICCV layout followed by an 18th plain
    /// 3x3 convolution (no batch norm, no ReLU).
    #[default]
    Published,
}

impl Layout {
    /// Number of 2D convolutions of the unary feature extractor.
    pub fn num_feature_convs(self) -> usize {
        match self {
            Layout::Iccv => 17,
            Layout::Published => 18,
        }
    }
}

/// Sizes of the network. Every field is serialised next to the weights it produced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NetConfig {
    /// `CH`: channels of the unary features; the cost volume has `2 CH` channels.
    pub channels: usize,
    /// `N`: number of inverse-depth hypotheses of the output (the sweep uses `N / 2`).
    pub num_invdepth: usize,
    /// `H`: rows of the output equirectangular inverse-depth map.
    pub out_height: usize,
    /// `W`: columns of the output equirectangular inverse-depth map.
    pub out_width: usize,
    /// Latitude range of the output, `+-phi_deg` degrees (45 in the paper).
    pub phi_deg: f64,
    /// Number of fisheye cameras of the rig (4 in the paper).
    pub num_cameras: usize,
    /// Rows of the network input image (fisheye images are resized to it).
    pub input_height: usize,
    /// Columns of the network input image.
    pub input_width: usize,
    /// Unary feature layout.
    pub layout: Layout,
}

impl Default for NetConfig {
    fn default() -> Self {
        Self::paper()
    }
}

impl NetConfig {
    /// The paper's configuration: `CH = 32`, `N = 192`, a `160 x 640` output over +-45
    /// degrees, four cameras with `768 x 800` inputs, published-weights layout.
    pub fn paper() -> Self {
        Self {
            channels: 32,
            num_invdepth: 192,
            out_height: 160,
            out_width: 640,
            phi_deg: 45.0,
            num_cameras: 4,
            input_height: 768,
            input_width: 800,
            layout: Layout::Published,
        }
    }

    /// A small configuration for CPU training and tests: `CH = 8`, `N = 64`, a `32 x 128`
    /// output over +-45 degrees, four cameras with `192 x 200` inputs.
    pub fn tiny() -> Self {
        Self {
            channels: 8,
            num_invdepth: 64,
            out_height: 32,
            out_width: 128,
            phi_deg: 45.0,
            num_cameras: 4,
            input_height: 192,
            input_width: 200,
            layout: Layout::Published,
        }
    }

    /// A preset by name: `paper` or `tiny`.
    ///
    /// # Errors
    /// [`NetError::UnknownPreset`] for any other name.
    pub fn preset(name: &str) -> Result<Self, NetError> {
        match name {
            "paper" => Ok(Self::paper()),
            "tiny" => Ok(Self::tiny()),
            other => Err(NetError::UnknownPreset(other.to_string())),
        }
    }

    /// Returns the configuration with another layout.
    pub fn with_layout(mut self, layout: Layout) -> Self {
        self.layout = layout;
        self
    }

    /// Number of swept spheres, `N / 2`.
    pub fn num_spheres(&self) -> usize {
        self.num_invdepth / 2
    }

    /// Channels of the cost volume, `2 CH`.
    pub fn cost_channels(&self) -> usize {
        2 * self.channels
    }

    /// Size `[rows, cols]` of the unary feature maps (stride-2 5x5 conv1 with padding 2).
    pub fn feature_size(&self) -> [usize; 2] {
        [
            (self.input_height - 1) / 2 + 1,
            (self.input_width - 1) / 2 + 1,
        ]
    }

    /// Checks that the network can be built and restores its output size.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] naming the field and what was expected.
    pub fn validate(&self) -> Result<(), NetError> {
        let invalid =
            |field: &'static str, message: String| NetError::InvalidConfig { field, message };
        if self.channels == 0 {
            return Err(invalid("channels", "must be at least 1".into()));
        }
        if self.num_cameras == 0 {
            return Err(invalid("num_cameras", "must be at least 1".into()));
        }
        if self.input_height < 2 || self.input_width < 2 {
            return Err(invalid(
                "input_height/input_width",
                format!(
                    "must be at least 2 x 2, got {} x {}",
                    self.input_height, self.input_width
                ),
            ));
        }
        if !(self.phi_deg > 0.0 && self.phi_deg <= 90.0) {
            return Err(invalid(
                "phi_deg",
                format!("must be in (0, 90], got {}", self.phi_deg),
            ));
        }
        let multiple = 2 << ENCODER_LEVELS;
        for (field, value) in [
            ("num_invdepth", self.num_invdepth),
            ("out_height", self.out_height),
            ("out_width", self.out_width),
        ] {
            if value == 0 || value % multiple != 0 {
                return Err(invalid(
                    field,
                    format!(
                        "{value} / 2 must be a positive multiple of {} (the 3D encoder halves the \
                         half-resolution cost volume {ENCODER_LEVELS} times and the decoder must \
                         restore it), i.e. {field} must be a multiple of {multiple}",
                        multiple / 2
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid() {
        NetConfig::paper().validate().unwrap();
        NetConfig::tiny().validate().unwrap();
        assert_eq!(NetConfig::paper().feature_size(), [384, 400]);
        assert_eq!(NetConfig::tiny().feature_size(), [96, 100]);
    }

    #[test]
    fn rejects_sizes_the_decoder_cannot_restore() {
        let config = NetConfig {
            out_height: 48,
            ..NetConfig::tiny()
        };
        let err = config.validate().unwrap_err().to_string();
        assert!(err.contains("out_height"), "{err}");
        assert!(err.contains("multiple of 32"), "{err}");
        let config = NetConfig {
            num_invdepth: 100,
            ..NetConfig::tiny()
        };
        assert!(config.validate().is_err());
        let config = NetConfig {
            channels: 0,
            ..NetConfig::tiny()
        };
        assert!(config.validate().is_err());
    }

    #[test]
    fn json_round_trip_and_defaults() {
        let config = NetConfig::tiny().with_layout(Layout::Iccv);
        let text = serde_json::to_string(&config).unwrap();
        assert!(text.contains("\"iccv\""));
        let back: NetConfig = serde_json::from_str(&text).unwrap();
        assert_eq!(back, config);
        let partial: NetConfig = serde_json::from_str("{\"channels\": 16}").unwrap();
        assert_eq!(partial.channels, 16);
        assert_eq!(partial.num_invdepth, 192);
        assert!(NetConfig::preset("huge").is_err());
    }
}
