//! Network configuration: sizes, layout variant and presets.

use serde::{Deserialize, Serialize};

use crate::error::NetError;

/// Most feature channels a cascade level may have: the host correlation kernel's limit (its
/// per-sample sums live on the stack).
pub const MAX_CHANNELS: usize = 64;

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

/// Which network family a configuration builds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// The paper's network ([`crate::OmniMvsNet`]): one full-resolution cost volume over
    /// `N / 2` spheres, 3D encoder-decoder, softargmin over `N`.
    #[default]
    OmniMvs,
    /// The coarse-to-fine network ([`crate::cascade::CascadeNet`]): a small cost volume at a
    /// quarter of the output resolution, then per-pixel hypotheses
    /// around the coarse estimate at half and full resolution.
    Cascade,
}

/// Sizes of the [`Family::Cascade`] network (ignored by the paper's network).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CascadeParams {
    /// Feature channels at strides 2, 4 and 8 of the input image.
    pub feature_channels: [usize; 3],
    /// Groups of the group-wise correlation at strides 2, 4 and 8.
    pub groups: [usize; 3],
    /// Spheres of the coarse cost volume, evenly spaced in index over `0..=N-1`.
    pub coarse_spheres: usize,
    /// Channels of the coarse 2D encoder-decoder (full, half and quarter resolution).
    pub coarse_channels: [usize; 3],
    /// Per-pixel hypotheses of the half- and full-resolution stages.
    pub stage_hypotheses: [usize; 2],
    /// Spacing of those hypotheses, in index units of `N`.
    pub stage_intervals: [f64; 2],
    /// Channels of the 2D convolutions of the half- and full-resolution stages.
    pub stage_channels: [usize; 2],
    /// Weights of the coarse, half- and full-resolution losses.
    pub loss_weights: [f64; 3],
    /// Context residual pairs at stride 8 after the base four convolutions, dilated 4 and 8
    /// in turn (a wider view for textureless and thin regions). Their residual branch starts
    /// at zero, so a trained network grows into them unchanged (`0`: the first cascades).
    #[serde(default)]
    pub context_pairs: usize,
    /// Refinement stages that can keep their centre: each answers
    /// `centre + g (soft argmax - centre)` with a per-pixel gate `g` in `0..1` learnt from
    /// its hidden features (starting near 1, where the stage behaves as without it).
    #[serde(default)]
    pub stage_gates: bool,
    /// Training only: weight of a cross-entropy between the coarse stage's distribution over
    /// its spheres and a Laplacian around the exact ground-truth index (scale half the sphere
    /// spacing), beside the L1 of its mean. The L1 is content with any spread whose mean is
    /// right; this asks for one peak at the truth (AcfNet's unimodal supervision). `0` (the
    /// first cascades, and left out of the file): no such term.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub coarse_distribution_weight: f64,
    /// Training only: the same cross-entropy for each refinement stage, over its per-pixel
    /// hypotheses (scale half their spacing; where the truth lies outside them, the target
    /// piles on the nearest). `0` (and left out of the file): no such term.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub refine_distribution_weight: f64,
    /// The photometric cue ([`crate::cascade::photo`]): every stage's cost volume gets one
    /// more channel, the ZNCC of the cameras' own images over a 5 x 5 window of its samples
    /// (no weights, no gradient). Its input weights start at zero, so a trained network grows
    /// into it unchanged. `false` (and left out of the file): the cascades before it.
    #[serde(default, skip_serializing_if = "is_false")]
    pub zncc_cue: bool,
    /// Training only: weight of sky pixels (ground-truth index exactly 0, inverse depth 0) in
    /// every stage's losses, against 1 for the others. The reference's protocol does not score
    /// sky; with weight 1 a things frame's large sky pulls answers near its edges, and near
    /// objects, toward far. `1` (the cascades before `cascade-11`, and left out of the file):
    /// sky counts as any pixel.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub sky_loss_weight: f64,
    /// Learnt (convex) upsampling of each stage's answer to the next stage's grid (RAFT's
    /// convex upsampling): every pixel of the finer grid takes a softmax-weighted mean of the
    /// 3 x 3 coarser pixels around its parent, the weights read from the finer stage's
    /// matching at each of them ([`crate::cascade::model::CandidateSelector`]), instead of the
    /// bilinear mean, which at a depth edge blends the two sides into a value near neither
    /// (the next stage then centres its hypotheses out of reach of both). The selectors start
    /// near the bilinear weights, so a trained network grows into them nearly unchanged.
    /// `false` (and left out of the file): bilinear.
    #[serde(default, skip_serializing_if = "is_false")]
    pub convex_upsampling: bool,
    /// With `convex_upsampling`, whether the full-resolution grid gets it too (`true`, and
    /// left out of the file: both grids, `cascade-13`) or only the half-resolution one
    /// (`false`: the full-resolution stage centres on the bilinear upsampling of the half
    /// stage). The full grid's selector is the dearer one: 9 candidates at each of the
    /// 102 400 pixels of the paper's grid, where the half grid's has a quarter of them.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub convex_upsampling_full: bool,
    /// With `zncc_cue`, the grid the coarse stage's cue is matched on: `1` (and left out of
    /// the file) the coarse grid itself, reading the quarter-size images; `2` the
    /// half-resolution grid at the same spheres, reading the half-size images, each coarse
    /// pixel taking the mean of its 2 x 2 (4x the samples). Fine repetitive texture (the
    /// stripes of things frames' rooms) is averaged away in the quarter-size images, and the
    /// coarse stage then misses by more than the refinement can reach where ZNCC+SGM, which
    /// matches the full-size images, does not.
    #[serde(default = "one_usize", skip_serializing_if = "is_one_usize")]
    pub coarse_cue_oversample: usize,
    /// With `zncc_cue`, the inverse depths the coarse cue is matched at per coarse sphere: `1`
    /// (and left out of the file) the sphere itself; an odd `m` up to 5, `m` depths evenly
    /// tiling the sphere's interval (offsets `j * spacing / m`, `|j| <= (m - 1) / 2`), the
    /// sphere taking the highest. Fine texture matches over a narrow range of depth, which
    /// falls between spheres 6 index units apart: on things validation frames the cue's best
    /// sphere (half-resolution grid) lies within +-9 of the truth in far untextured-edge
    /// regions for 75.3 % of the pixels with 1, 79.7 % with 3 (80.4 % for all 192 depths).
    #[serde(default = "one_usize", skip_serializing_if = "is_one_usize")]
    pub coarse_cue_depths: usize,
    /// With `zncc_cue`, a second cue channel for the coarse stage (`true`; `false`, and left
    /// out of the file: none): the cue's costs `(1 - zncc) / 2` at all its depths, in index
    /// order, aggregated along 8 wrapping paths over the coarse grid by semi-global matching
    /// ([`crate::cascade::photo::COARSE_SGM_P1`], [`crate::cascade::photo::COARSE_SGM_P2`]), each sphere the
    /// lowest excess over the pixel's best, mapped to `1 - 2 min(excess, 1)`. The 3D
    /// regularisation of the coarse stage sees a few pixels around; the paths carry the
    /// evidence of a whole wall: on things validation frames the aggregated cue's best sphere
    /// lies within +-9 of the truth for 93.9-96.9 % of far pixels away from edges, the network
    /// (`cascade-23`) for 83.0 % and the raw cue for 78.8 % (`research/cascade.md`).
    /// Its first convolution's input grows by one channel per sphere (zero weights when
    /// switched on from weights without it).
    #[serde(default, skip_serializing_if = "is_false")]
    pub coarse_cue_sgm: bool,
}

impl CascadeParams {
    /// The input channels per hypothesis of refinement stage `i` (0: half, 1: full
    /// resolution): its groups' correlations, the visibility and the photometric cue with
    /// `zncc_cue`.
    pub fn stage_evidence_channels(&self, i: usize) -> usize {
        self.groups[1 - i] + 1 + usize::from(self.zncc_cue)
    }

    /// The input channels per sphere of the coarse stage: the stride-8 groups' correlations,
    /// the visibility, the photometric cue with `zncc_cue` and the aggregated cue with
    /// `coarse_cue_sgm`.
    pub fn coarse_evidence_channels(&self) -> usize {
        self.groups[2] + 1 + usize::from(self.zncc_cue) + usize::from(self.coarse_cue_sgm)
    }
}

fn one_usize() -> usize {
    1
}

fn is_one_usize(value: &usize) -> bool {
    *value == 1
}

fn yes() -> bool {
    true
}

fn is_true(value: &bool) -> bool {
    *value
}

fn is_zero(value: &f64) -> bool {
    *value == 0.0
}

fn one() -> f64 {
    1.0
}

fn is_one(value: &f64) -> bool {
    *value == 1.0
}

fn is_false(value: &bool) -> bool {
    !*value
}

impl Default for CascadeParams {
    fn default() -> Self {
        Self {
            feature_channels: [8, 16, 16],
            groups: [4, 4, 8],
            coarse_spheres: 32,
            coarse_channels: [48, 64, 96],
            stage_hypotheses: [8, 5],
            stage_intervals: [2.0, 1.0],
            stage_channels: [32, 16],
            loss_weights: [0.5, 1.0, 2.0],
            context_pairs: 0,
            stage_gates: false,
            coarse_distribution_weight: 0.0,
            refine_distribution_weight: 0.0,
            zncc_cue: false,
            sky_loss_weight: 1.0,
            convex_upsampling: false,
            convex_upsampling_full: true,
            coarse_cue_oversample: 1,
            coarse_cue_depths: 1,
            coarse_cue_sgm: false,
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
    /// Number of fisheye cameras of the rig (4 in the paper): what the paper's network
    /// concatenates, and the rig the cascade was trained on (which runs on any count of
    /// [`CASCADE_CAMERAS`]).
    pub num_cameras: usize,
    /// Rows of the network input image (fisheye images are resized to it).
    pub input_height: usize,
    /// Columns of the network input image.
    pub input_width: usize,
    /// Unary feature layout.
    pub layout: Layout,
    /// Network family (absent in older files: the paper's network).
    pub family: Family,
    /// Sizes of the cascade network (only for [`Family::Cascade`]). Files may still name the
    /// experiment switches removed in 0.2 ([`REMOVED_SWITCHES`]) at their default value.
    #[serde(deserialize_with = "read_cascade_params")]
    pub cascade: CascadeParams,
}

/// How many cameras the cascade network runs on. What it computes across cameras does not
/// depend on their number or order: the mean over camera pairs of the features' products,
/// the share of cameras that see a sample, the mean ZNCC over pairs.
pub const CASCADE_CAMERAS: std::ops::RangeInclusive<usize> = 2..=8;

impl NetConfig {
    /// Whether the network runs on `count` cameras (of `what`, named in the error): the
    /// cascade on [`CASCADE_CAMERAS`], the paper's network, which concatenates its cameras'
    /// volumes, on exactly `num_cameras`.
    ///
    /// # Errors
    /// [`NetError::Cameras`] saying what the network takes.
    pub fn check_cameras(&self, count: usize, what: impl Into<String>) -> Result<(), NetError> {
        let supported = match self.family {
            Family::Cascade if CASCADE_CAMERAS.contains(&count) => return Ok(()),
            Family::Cascade => format!(
                "the cascade network runs on {} to {} cameras",
                CASCADE_CAMERAS.start(),
                CASCADE_CAMERAS.end()
            ),
            Family::OmniMvs if count == self.num_cameras => return Ok(()),
            Family::OmniMvs => format!(
                "this network concatenates exactly {} cameras (the cascade takes {} to {})",
                self.num_cameras,
                CASCADE_CAMERAS.start(),
                CASCADE_CAMERAS.end()
            ),
        };
        Err(NetError::Cameras {
            what: what.into(),
            count,
            supported,
        })
    }
}

/// Experiment switches of [`CascadeParams`] removed in 0.2 (no shipped network and no step of
/// the bundled cascade's lineage turned them on), each with the value that left it off
/// (`research/cascade.md`, "switches removed from the code"). A configuration file that names
/// one at that value still loads; one that sets it otherwise is refused.
pub const REMOVED_SWITCHES: &[(&str, &str)] = &[
    ("neighbour_extremes", "[0, 0]"),
    ("neighbour_hypotheses", "[0, 0]"),
    ("neighbour_start_score", "-5.0"),
    ("neighbour_gain", "1.0"),
    ("coarse_score_sgm", "null"),
    ("mid_cue_sgm", "false"),
    ("coarse_scale", "4"),
    ("coarse_stride4", "false"),
    ("same_grid_selector", "false"),
    ("coarse_squeeze", "0"),
];

/// Whether two JSON values are equal, numbers by value (`1` and `1.0` alike).
fn same_json(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same_json(x, y))
        }
        _ => a == b,
    }
}

/// [`CascadeParams`] from a configuration file, which may name a removed switch
/// ([`REMOVED_SWITCHES`]) at its default value.
fn read_cascade_params<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> Result<CascadeParams, D::Error> {
    use serde::de::Error;
    let mut map = serde_json::Map::<String, serde_json::Value>::deserialize(deserializer)?;
    for &(name, default) in REMOVED_SWITCHES {
        let Some(value) = map.remove(name) else {
            continue;
        };
        let off: serde_json::Value = serde_json::from_str(default).map_err(D::Error::custom)?;
        if !same_json(&value, &off) {
            return Err(D::Error::custom(format!(
                "`cascade.{name}` was an experiment switch removed in 0.2 (off at {default}); \
                 this file sets it to {value}"
            )));
        }
    }
    CascadeParams::deserialize(serde_json::Value::Object(map)).map_err(D::Error::custom)
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
            family: Family::OmniMvs,
            cascade: CascadeParams::default(),
        }
    }

    /// The coarse-to-fine network at the paper's output: `160 x 640` over +-45 degrees,
    /// `N = 192`, four cameras with `768 x 800` inputs; a 32-sphere cost volume at `40 x 160`,
    /// then 8 hypotheses per pixel at `80 x 320` and 5 at `160 x 640`.
    pub fn cascade() -> Self {
        Self {
            family: Family::Cascade,
            channels: 8,
            ..Self::paper()
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
            family: Family::OmniMvs,
            cascade: CascadeParams::default(),
        }
    }

    /// A preset by name: `paper`, `tiny` or `cascade`.
    ///
    /// # Errors
    /// [`NetError::UnknownPreset`] for any other name.
    pub fn preset(name: &str) -> Result<Self, NetError> {
        match name {
            "paper" => Ok(Self::paper()),
            "tiny" => Ok(Self::tiny()),
            "cascade" => Ok(Self::cascade()),
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
        if self.family == Family::Cascade {
            return self.validate_cascade();
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

    /// The output grid sizes `[rows, cols]` of the cascade's coarse, half- and
    /// full-resolution stages.
    pub fn cascade_sizes(&self) -> [[usize; 2]; 3] {
        let [h, w] = [self.out_height, self.out_width];
        [[h / 4, w / 4], [h / 2, w / 2], [h, w]]
    }

    /// Feature-map sizes `[rows, cols]` at strides 2, 4 and 8 of the input (each a 3x3 or 5x5
    /// stride-2 convolution with "same" padding).
    pub fn cascade_feature_sizes(&self) -> [[usize; 2]; 3] {
        let half = |[r, c]: [usize; 2]| [(r - 1) / 2 + 1, (c - 1) / 2 + 1];
        let s2 = half([self.input_height, self.input_width]);
        let s4 = half(s2);
        [s2, s4, half(s4)]
    }

    fn validate_cascade(&self) -> Result<(), NetError> {
        self.validate_cascade_grid()?;
        self.validate_cascade_cues()?;
        self.validate_cascade_sizes()
    }

    /// The output grid.
    fn validate_cascade_grid(&self) -> Result<(), NetError> {
        let invalid =
            |field: &'static str, message: String| NetError::InvalidConfig { field, message };
        for (field, value) in [
            ("out_height", self.out_height),
            ("out_width", self.out_width),
        ] {
            if value == 0 || value % 16 != 0 {
                return Err(invalid(
                    field,
                    format!(
                        "{value} must be a positive multiple of 16 (the coarse stage runs at a \
                         quarter of the output and its encoder halves that twice)"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The photometric cues' settings.
    fn validate_cascade_cues(&self) -> Result<(), NetError> {
        let invalid =
            |field: &'static str, message: String| NetError::InvalidConfig { field, message };
        let p = &self.cascade;
        if !matches!(p.coarse_cue_oversample, 1 | 2) {
            return Err(invalid(
                "cascade.coarse_cue_oversample",
                format!(
                    "{} must be 1 (the coarse grid) or 2 (the half-resolution grid)",
                    p.coarse_cue_oversample
                ),
            ));
        }
        if !matches!(p.coarse_cue_depths, 1 | 3 | 5) {
            return Err(invalid(
                "cascade.coarse_cue_depths",
                format!("{} must be 1, 3 or 5", p.coarse_cue_depths),
            ));
        }
        if p.coarse_cue_sgm && !p.zncc_cue {
            return Err(invalid(
                "cascade.coarse_cue_sgm",
                "needs `zncc_cue` (it aggregates that cue)".into(),
            ));
        }
        Ok(())
    }

    /// The stages' sizes (spheres, channels, groups, hypotheses) and the losses' weights and
    /// the refinement spacing.
    fn validate_cascade_sizes(&self) -> Result<(), NetError> {
        let invalid =
            |field: &'static str, message: String| NetError::InvalidConfig { field, message };
        let p = &self.cascade;
        if p.coarse_spheres < 2 || p.coarse_spheres > self.num_invdepth {
            return Err(invalid(
                "cascade.coarse_spheres",
                format!(
                    "{} must be at least 2 and at most num_invdepth = {}",
                    p.coarse_spheres, self.num_invdepth
                ),
            ));
        }
        for (level, (&ch, &g)) in p.feature_channels.iter().zip(&p.groups).enumerate() {
            if ch > MAX_CHANNELS {
                return Err(invalid(
                    "cascade.feature_channels",
                    format!(
                        "level {level}: {ch} channels, at most {} (the host correlation's limit)",
                        MAX_CHANNELS
                    ),
                ));
            }
            if ch == 0 || g == 0 || ch % g != 0 {
                return Err(invalid(
                    "cascade.groups",
                    format!(
                        "level {level}: {g} groups must divide {ch} feature channels (both > 0)"
                    ),
                ));
            }
        }
        if p.coarse_channels.contains(&0)
            || p.stage_channels.contains(&0)
            || p.stage_hypotheses.iter().any(|&k| k < 2)
        {
            return Err(invalid(
                "cascade",
                "channels must be positive and every stage needs at least 2 hypotheses".into(),
            ));
        }
        for (field, w) in [
            (
                "cascade.coarse_distribution_weight",
                p.coarse_distribution_weight,
            ),
            (
                "cascade.refine_distribution_weight",
                p.refine_distribution_weight,
            ),
            ("cascade.sky_loss_weight", p.sky_loss_weight),
        ] {
            if !(w.is_finite() && w >= 0.0) {
                return Err(invalid(
                    field,
                    format!("expected a finite weight >= 0, got {w}"),
                ));
            }
        }
        if p.stage_intervals.iter().any(|&d| d.is_nan() || d <= 0.0) {
            return Err(invalid(
                "cascade.stage_intervals",
                format!("must be positive, got {:?}", p.stage_intervals),
            ));
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
        let cascade = NetConfig::cascade();
        cascade.validate().unwrap();
        assert_eq!(cascade.cascade_sizes(), [[40, 160], [80, 320], [160, 640]]);
        assert_eq!(
            cascade.cascade_feature_sizes(),
            [[384, 400], [192, 200], [96, 100]]
        );
    }

    #[test]
    fn cascade_rejects_sizes_it_cannot_use() {
        let config = NetConfig {
            out_height: 40,
            ..NetConfig::cascade()
        };
        let err = config.validate().unwrap_err().to_string();
        assert!(err.contains("out_height"), "{err}");
        let mut config = NetConfig::cascade();
        config.cascade.coarse_spheres = 1;
        assert!(config.validate().is_err());
        let mut config = NetConfig::cascade();
        config.cascade.groups[1] = 5;
        assert!(
            config
                .validate()
                .unwrap_err()
                .to_string()
                .contains("groups")
        );
        // Files written before the family existed are the paper's network.
        let old: NetConfig = serde_json::from_str("{\"channels\": 8}").unwrap();
        assert_eq!(old.family, Family::OmniMvs);
    }

    #[test]
    fn the_sky_loss_weight_is_one_unless_written() {
        // Files written before the field existed weigh sky as any pixel; weight 1 is left out.
        let cascade = NetConfig::cascade();
        let json = serde_json::to_string(&cascade).unwrap();
        assert!(!json.contains("sky_loss_weight"), "{json}");
        let read: NetConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(read.cascade.sky_loss_weight, 1.0);
        let mut light = NetConfig::cascade();
        light.cascade.sky_loss_weight = 0.1;
        let json = serde_json::to_string(&light).unwrap();
        assert!(json.contains("\"sky_loss_weight\":0.1"), "{json}");
        assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), light);
        light.cascade.sky_loss_weight = -0.5;
        let err = light.validate().unwrap_err().to_string();
        assert!(err.contains("cascade.sky_loss_weight"), "{err}");
    }

    #[test]
    fn convex_upsampling_is_off_unless_written() {
        // Files written before the field existed upsample bilinearly; `false` is left out.
        let json = serde_json::to_string(&NetConfig::cascade()).unwrap();
        assert!(!json.contains("convex_upsampling"), "{json}");
        let read: NetConfig = serde_json::from_str(&json).unwrap();
        assert!(!read.cascade.convex_upsampling);
        let mut learnt = NetConfig::cascade();
        learnt.cascade.convex_upsampling = true;
        let json = serde_json::to_string(&learnt).unwrap();
        assert!(json.contains("\"convex_upsampling\":true"), "{json}");
        assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), learnt);
        // Both grids unless written (cascade-13's files); the half grid only is written.
        assert!(!json.contains("convex_upsampling_full"), "{json}");
        assert!(learnt.cascade.convex_upsampling_full);
        learnt.cascade.convex_upsampling_full = false;
        let json = serde_json::to_string(&learnt).unwrap();
        assert!(json.contains("\"convex_upsampling_full\":false"), "{json}");
        assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), learnt);
    }

    #[test]
    fn the_coarse_cue_is_matched_on_the_coarse_grid_unless_written() {
        let json = serde_json::to_string(&NetConfig::cascade()).unwrap();
        assert!(!json.contains("coarse_cue_oversample"), "{json}");
        let mut fine = NetConfig::cascade();
        fine.cascade.coarse_cue_oversample = 2;
        let json = serde_json::to_string(&fine).unwrap();
        assert!(json.contains("\"coarse_cue_oversample\":2"), "{json}");
        assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), fine);
        for bad in [0, 3, 4] {
            fine.cascade.coarse_cue_oversample = bad;
            let err = fine.validate().unwrap_err().to_string();
            assert!(err.contains("cascade.coarse_cue_oversample"), "{err}");
        }
        let mut deep = NetConfig::cascade();
        assert!(!json.contains("coarse_cue_depths"), "{json}");
        for bad in [0, 2, 7] {
            deep.cascade.coarse_cue_depths = bad;
            let err = deep.validate().unwrap_err().to_string();
            assert!(err.contains("cascade.coarse_cue_depths"), "{err}");
        }
        deep.cascade.coarse_cue_depths = 3;
        let json = serde_json::to_string(&deep).unwrap();
        assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), deep);
        // The aggregated cue: off unless written, and only with the cue it aggregates.
        assert!(!json.contains("coarse_cue_sgm"), "{json}");
        deep.cascade.coarse_cue_sgm = true;
        let err = deep.validate().unwrap_err().to_string();
        assert!(err.contains("cascade.coarse_cue_sgm"), "{err}");
        deep.cascade.zncc_cue = true;
        deep.validate().unwrap();
        let json = serde_json::to_string(&deep).unwrap();
        assert!(json.contains("\"coarse_cue_sgm\":true"), "{json}");
        assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), deep);
        let mut wide = NetConfig::cascade();
        wide.cascade.feature_channels[2] = 128;
        let err = wide.validate().unwrap_err().to_string();
        assert!(err.contains("cascade.feature_channels"), "{err}");
    }

    #[test]
    fn removed_switches_are_read_at_their_default_only() {
        let json = serde_json::to_string(&NetConfig::cascade()).unwrap();
        let with = |field: &str| json.replace("\"cascade\":{", &format!("\"cascade\":{{{field},"));
        for off in [
            "\"neighbour_extremes\":[0,0]",
            "\"neighbour_hypotheses\":[0,0]",
            "\"neighbour_start_score\":-5",
            "\"neighbour_gain\":1.0",
            "\"coarse_score_sgm\":null",
            "\"mid_cue_sgm\":false",
            "\"coarse_scale\":4",
            "\"coarse_stride4\":false",
            "\"same_grid_selector\":false",
            "\"coarse_squeeze\":0",
        ] {
            let read: NetConfig = serde_json::from_str(&with(off)).unwrap();
            assert_eq!(read, NetConfig::cascade(), "{off}");
        }
        for on in [
            "\"neighbour_hypotheses\":[0,2]",
            "\"neighbour_gain\":30.0",
            "\"coarse_score_sgm\":{\"p1\":1.0,\"p2\":4.0,\"temperature\":8.0}",
            "\"mid_cue_sgm\":true",
            "\"coarse_scale\":2",
            "\"coarse_stride4\":true",
            "\"same_grid_selector\":true",
            "\"coarse_squeeze\":64",
        ] {
            let err = serde_json::from_str::<NetConfig>(&with(on))
                .unwrap_err()
                .to_string();
            assert!(err.contains("removed in 0.2"), "{err}");
        }
        let typo = with("\"neighbour_gains\":1.0");
        assert!(serde_json::from_str::<NetConfig>(&typo).is_err());
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
