//! Parsers for argument values shared by several subcommands.

use std::path::PathBuf;

use omnimvs_camera::FrameChoice;
use omnimvs_net::NetConfig;
use omnimvs_synth::SceneKind;
use omnimvs_synth::SynthError;
use omnimvs_synth::random_rig::{RANDOM_PREFIX, parse_random_rig};
use omnimvs_synth::rig::{PRESET_NAME, RigSource, load_rig_with};

/// The spherical sweep of a command: output grid and hypotheses (`sgm`, `eval`, `lut`), the
/// paper's by default: 160x640 over +-45 degrees, N = 192.
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct SweepArgs {
    /// Output grid, HEIGHTxWIDTH (`eval` resamples every method's output to it; SGM runs at
    /// it).
    #[arg(long, default_value = "160x640")]
    pub size: Size,
    /// Latitude range of the grid, +-degrees.
    #[arg(long, default_value_t = 45.0)]
    pub phi_deg: f64,
    /// Number of inverse-depth hypotheses N (`eval`: the unit of its error E).
    #[arg(long, default_value_t = 192)]
    pub ndepth: usize,
}

impl SweepArgs {
    /// The sweep of `dataset` (its minimum depth) on this grid.
    pub fn spec(
        &self,
        dataset: &omnimvs_data::Dataset,
    ) -> Result<omnimvs_sweep::SweepSpec, omnimvs_data::DataError> {
        dataset.sweep_spec(self.size.height, self.size.width, self.phi_deg, self.ndepth)
    }
}

/// `HxW`, e.g. `160x640`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Size {
    pub height: usize,
    pub width: usize,
}

impl std::str::FromStr for Size {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("expected HEIGHTxWIDTH such as 160x640, found {s:?}");
        let (h, w) = s.split_once(['x', 'X']).ok_or_else(bad)?;
        let height: usize = h.trim().parse().map_err(|_| bad())?;
        let width: usize = w.trim().parse().map_err(|_| bad())?;
        if height == 0 || width == 0 {
            return Err(bad());
        }
        Ok(Self { height, width })
    }
}

impl std::fmt::Display for Size {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.height, self.width)
    }
}

/// `--preset`: the architecture sizes of a network ([`NetConfig`]'s presets).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// The paper's OmniMVS network (CH 32, N 192, 160x640 output).
    Paper,
    /// The paper's network at a quarter of its input size (the bundled `tiny` model's sizes).
    Tiny,
    /// The coarse-to-fine network for CPUs at the paper's output grid.
    Cascade,
}

impl Preset {
    /// The name on the command line and in `NetConfig::preset`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Tiny => "tiny",
            Self::Cascade => "cascade",
        }
    }

    /// The network configuration of the preset.
    pub fn config(self) -> NetConfig {
        match self {
            Self::Paper => NetConfig::paper(),
            Self::Tiny => NetConfig::tiny(),
            Self::Cascade => NetConfig::cascade(),
        }
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// `--method` of `eval`: a depth estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// A network (`--weights`).
    Net,
    /// The classical method, ZNCC + SGM.
    Sgm,
    /// SGM on the bundled MC-CNN-style learned cost (MC-CNN+SGM).
    Mccnn,
    /// SGM on the bundled SweepNet-style learned cost (SweepNet+SGM).
    Sweepnet,
}

/// `--cost` of `sgm`: the matching cost that SGM regularises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Cost {
    /// 9x9 ZNCC over every camera pair (the paper's ZNCC+SGM).
    Zncc,
    /// The MC-CNN-style learned cost (siamese features, cosine over camera pairs).
    Mccnn,
    /// The SweepNet-style learned cost (a network on the warped images of all cameras).
    Sweepnet,
}

/// `--kind` of `synth`: the kinds of scene a dataset can hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// Random objects in a room or under a sky (OmniThings-like).
    Things,
    /// Furnished rooms (OmniHouse-like).
    House,
}

impl From<Kind> for SceneKind {
    fn from(kind: Kind) -> Self {
        match kind {
            Kind::Things => Self::Things,
            Kind::House => Self::House,
        }
    }
}

/// `--rig` of `synth`: the published rig or a reference `config.yaml`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RigArg {
    /// The published 4-camera rig (`sunny`).
    Published,
    /// A rig file: a reference `config.yaml` (its `config.omnimvs_sweep_min_depth` is the
    /// minimum depth), a Basalt `calibration.json`, a Kalibr `camchain.yaml`.
    Config(PathBuf),
    /// A random rig drawn from a seed (`random:SEED`, [`omnimvs_synth::random_rig`]).
    Random(u64),
}

impl RigArg {
    /// Reads a `--rig` value: `sunny` (or its older name `preset`), `random:SEED` or a path.
    pub fn parse(text: &str) -> Result<Self, String> {
        if let Some(seed) = parse_random_rig(text).map_err(|e| e.to_string())? {
            return Ok(Self::Random(seed));
        }
        Ok(match text {
            PRESET_NAME | "preset" => Self::Published,
            path => Self::Config(PathBuf::from(path)),
        })
    }

    /// Loads the rig and its minimum depth (`min_depth_m` instead of the file's) in `frame`.
    ///
    /// # Errors
    /// A file that cannot be read or lacks a field; a fitted frame the rig cannot have.
    pub fn load(
        &self,
        min_depth_m: Option<f64>,
        frame: FrameChoice,
    ) -> Result<RigSource, SynthError> {
        match self {
            Self::Published => load_rig_with(PRESET_NAME, min_depth_m, frame),
            Self::Config(path) => load_rig_with(&path.to_string_lossy(), min_depth_m, frame),
            Self::Random(seed) => {
                load_rig_with(&format!("{RANDOM_PREFIX}{seed}"), min_depth_m, frame)
            }
        }
    }
}

impl std::fmt::Display for RigArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Published => f.write_str(PRESET_NAME),
            Self::Config(path) => write!(f, "{}", path.display()),
            Self::Random(seed) => write!(f, "{RANDOM_PREFIX}{seed}"),
        }
    }
}

/// Help of every `--backend` option.
pub const BACKEND_HELP: &str = "Compute backend: cpu (burn flex, the default), libtorch, \
     libtorch-cuda[:N], wgpu[:N], vulkan or wgpu-cpu; all but cpu need a build with the \
     `libtorch` or `wgpu` Cargo feature (see the README)";

/// Parses a `--backend` value and checks that this build has it.
pub fn parse_backend(text: &str) -> Result<omnimvs_net::Backend, String> {
    let backend: omnimvs_net::Backend = text.parse().map_err(|e| format!("{e}"))?;
    backend.device().map_err(|e| format!("{e}"))?;
    Ok(backend)
}

/// Parses the path of an output file and checks, before any work is done, that its folder
/// exists (a report written after minutes of benchmarking must not fail then).
pub fn parse_output_file(text: &str) -> Result<std::path::PathBuf, String> {
    let path = std::path::PathBuf::from(text);
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if path.file_name().is_none() || !folder.is_dir() {
        return Err(format!(
            "expected a file in an existing folder, but {} is not a folder",
            folder.display()
        ));
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_sizes() {
        assert_eq!(
            "160x640".parse::<Size>().unwrap(),
            Size {
                height: 160,
                width: 640
            }
        );
        assert!("160".parse::<Size>().is_err());
        assert!("0x640".parse::<Size>().is_err());
    }

    #[test]
    fn presets_keep_their_names() {
        use clap::ValueEnum;
        for preset in Preset::value_variants() {
            let name = preset.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(name, preset.name());
            assert_eq!(NetConfig::preset(&name).unwrap(), preset.config());
        }
    }

    #[test]
    fn rigs_parse() {
        assert_eq!(RigArg::parse("sunny").unwrap(), RigArg::Published);
        assert_eq!(
            RigArg::parse("a/config.yaml").unwrap(),
            RigArg::Config("a/config.yaml".into())
        );
    }
}
