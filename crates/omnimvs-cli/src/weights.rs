//! Where a command's network comes from: the bundled model (compiled into the binary, so it
//! works from any folder), a weights file, or a random initialisation.

use std::path::PathBuf;

use anyhow::bail;
use anyhow::{Context, Result};
use burn::tensor::Device;
use omnimvs_net::NetEstimator;
use omnimvs_net::bundled::{BundledModel, PickChoice};
use omnimvs_net::weights::{AnyNet, load_any, load_family};
use omnimvs_net::{CascadeNet, Family};
use omnimvs_net::{NetConfig, OmniMvsNet};

/// `--weights` value that names the default bundled model, the cascade (also the default
/// value of `infer` and `eval`).
pub const BUNDLED: &str = "bundled";
/// `--weights` value that asks for a randomly initialised network.
pub const RANDOM: &str = "random";

/// A `--weights` value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Weights {
    /// A model bundled into the binary (`bundled`: the default one, the cascade, or by name:
    /// `cascade`, `tiny`).
    Bundled(BundledModel),
    /// A randomly initialised network of the `--preset` sizes.
    Random,
    /// Our `.safetensors` (with its `.json`) or a reference PyTorch checkpoint.
    File(PathBuf),
}

impl Weights {
    /// Reads a `--weights` value: `bundled`, a bundled model's name, `random`, or a path.
    pub fn parse(text: &str) -> Result<Self, String> {
        Ok(match text {
            BUNDLED => Self::Bundled(BundledModel::DEFAULT),
            RANDOM => Self::Random,
            name => match BundledModel::from_name(name) {
                Some(model) => Self::Bundled(model),
                None => Self::File(PathBuf::from(name)),
            },
        })
    }

    /// A short name for tables and file names: the file stem, the bundled model's name or
    /// `random`.
    pub fn stem(&self) -> String {
        match self {
            Self::Bundled(model) => model.name().into(),
            Self::Random => RANDOM.into(),
            Self::File(path) => path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
        }
    }

    /// Loads the paper's network on `device`; `preset` sizes a PyTorch checkpoint or a random
    /// network (our files carry their own sizes). For the commands that need the paper's
    /// family (`parity`); the others take either family with [`Weights::load_family`].
    ///
    /// # Errors
    /// An unknown preset, a file that cannot be read or does not match the network, or a
    /// cascade (the bundled default is one: `--weights tiny` names the paper's).
    pub fn load(&self, preset: &str, device: &Device) -> Result<OmniMvsNet> {
        let base = NetConfig::preset(preset)?;
        Ok(match self {
            Self::Bundled(model) => match model.load(device)? {
                AnyNet::OmniMvs(net) => *net,
                AnyNet::Cascade(_) => bail!(
                    "the bundled `{model}` model is the cascade network, not the paper's; \
                     this command needs the paper's (e.g. --weights tiny)"
                ),
            },
            Self::Random => {
                eprintln!(
                    "warning: randomly initialised `{preset}` network, its outputs are meaningless"
                );
                OmniMvsNet::new(&base, device)?
            }
            Self::File(path) => load_any(path, &base, device)
                .with_context(|| format!("loading weights {}", path.display()))?,
        })
    }
}

impl Weights {
    /// Loads a network of either family on `device`: our files say which, a PyTorch
    /// checkpoint is the paper's network, and `preset` sizes a PyTorch checkpoint or a random
    /// network (`cascade` gives a random cascade).
    ///
    /// # Errors
    /// An unknown preset, or a file that cannot be read or does not match the network.
    pub fn load_family(&self, preset: &str, device: &Device) -> Result<AnyNet> {
        let base = NetConfig::preset(preset)?;
        Ok(match self {
            Self::File(path) => load_family(path, &base, device)
                .with_context(|| format!("loading weights {}", path.display()))?,
            Self::Random if base.family == Family::Cascade => {
                eprintln!(
                    "warning: randomly initialised `{preset}` network, its outputs are meaningless"
                );
                AnyNet::Cascade(Box::new(CascadeNet::new(&base, device)?))
            }
            Self::Bundled(model) => model.load(device)?,
            Self::Random => AnyNet::OmniMvs(Box::new(self.load(preset, device)?)),
        })
    }
}

/// `clap`'s reader of a `--pick` value (the learnt pick after the cascade network,
/// `omnimvs_net::pick`): `auto`, `off`, `single`, `chain` or paths.
pub fn parse_pick(text: &str) -> Result<PickChoice, String> {
    Ok(PickChoice::parse(text))
}

/// `estimator` with the pick that `pick` gives after `weights`' network.
///
/// # Errors
/// A pick file that cannot be read or does not fit the rig.
pub fn apply_pick(
    pick: &PickChoice,
    weights: &Weights,
    estimator: NetEstimator,
) -> Result<NetEstimator> {
    let model = match weights {
        Weights::Bundled(model) => Some(*model),
        _ => None,
    };
    let refiner = pick.load(model).with_context(|| format!("--pick {pick}"))?;
    let (estimator, note) = estimator
        .with_chosen_pick(pick, refiner)
        .context("--pick")?;
    if let Some(note) = note {
        eprintln!("note: {note}");
    }
    Ok(estimator)
}

impl std::fmt::Display for Weights {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Bundled(model) => write!(f, "{BUNDLED} {model} ({})", model.label()),
            Self::Random => f.write_str(RANDOM),
            Self::File(path) => write!(f, "{}", path.display()),
        }
    }
}

impl serde::Serialize for Weights {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}
