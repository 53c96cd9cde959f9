//! The models compiled into the library (`models/` of the repository): they work from any
//! folder, with no file to find.
//!
//! - `cascade` (the default, [`BundledModel::DEFAULT`]): the cascade network (see `cascade`),
//!   answering at the paper's 160x640 with N = 192 from the full-size inputs. Its weights and
//!   the commands that trained them are in `models/README.md` and `models/recipes/`.
//! - `tiny`: the paper's architecture at 192x200 inputs, answering at 32x128 with N = 64 (the
//!   default before the cascade; what needs the paper's network family names it).

use std::path::Path;

use burn::tensor::Device;

use crate::error::NetError;
use crate::pick::PickRefiner;
use crate::weights::{AnyNet, load_any_bytes};

/// A model compiled into the library.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BundledModel {
    /// `models/omnimvs-tiny.*`: the paper's network, small.
    Tiny,
    /// `models/omnimvs-cascade.*`: the cascade network at full resolution.
    Cascade,
}

impl BundledModel {
    /// Every bundled model.
    pub const ALL: [Self; 2] = [Self::Tiny, Self::Cascade];

    /// The model used when none is named.
    pub const DEFAULT: Self = Self::Cascade;

    /// Its short name (`tiny`, `cascade`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Tiny => "tiny",
            Self::Cascade => "cascade",
        }
    }

    /// The model of a short name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Where its weights live in the repository (named in errors and reports).
    pub fn label(self) -> &'static str {
        match self {
            Self::Tiny => "models/omnimvs-tiny.safetensors",
            Self::Cascade => "models/omnimvs-cascade.safetensors",
        }
    }

    /// Its configuration (the `.json` beside the weights).
    pub fn config_json(self) -> &'static str {
        match self {
            Self::Tiny => include_str!("../../../models/omnimvs-tiny.json"),
            Self::Cascade => include_str!("../../../models/omnimvs-cascade.json"),
        }
    }

    /// Its weights (`.safetensors`).
    pub fn bytes(self) -> &'static [u8] {
        match self {
            Self::Tiny => include_bytes!("../../../models/omnimvs-tiny.safetensors"),
            Self::Cascade => include_bytes!("../../../models/omnimvs-cascade.safetensors"),
        }
    }

    /// The learnt pick trained on this model's answers, which runs after it unless left out
    /// ([`crate::pick`]): the cascade's; `None` for `tiny`.
    ///
    /// # Errors
    /// [`NetError`] if the compiled-in file does not match the pick (a build defect).
    pub fn pick(self) -> Result<Option<PickRefiner>, NetError> {
        match self {
            Self::Cascade => PickRefiner::bundled().map(Some),
            Self::Tiny => Ok(None),
        }
    }

    /// Its pick followed by the second pick trained on that pick's answers: the
    /// cascade's; `None` for `tiny`.
    ///
    /// # Errors
    /// [`NetError`] if the compiled-in files do not match the pick (a build defect).
    pub fn pick_chain(self) -> Result<Option<PickRefiner>, NetError> {
        match self {
            Self::Cascade => PickRefiner::bundled_chain().map(Some),
            Self::Tiny => Ok(None),
        }
    }

    /// The network, on `device`.
    ///
    /// # Errors
    /// [`NetError`] if the compiled-in files do not match their network (a build defect).
    pub fn load(self, device: &Device) -> Result<AnyNet, NetError> {
        load_any_bytes(
            Path::new(self.label()),
            self.config_json(),
            self.bytes(),
            device,
        )
    }
}

impl std::fmt::Display for BundledModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Family;

    #[test]
    fn every_bundled_model_loads_as_its_family() {
        let device = Device::flex();
        for model in BundledModel::ALL {
            assert_eq!(BundledModel::from_name(model.name()), Some(model));
            let net = model.load(&device).unwrap();
            let (family, out) = match &net {
                AnyNet::OmniMvs(n) => (Family::OmniMvs, [n.config.out_height, n.config.out_width]),
                AnyNet::Cascade(n) => (Family::Cascade, [n.config.out_height, n.config.out_width]),
            };
            let expected = match model {
                BundledModel::Tiny => (Family::OmniMvs, [32, 128]),
                BundledModel::Cascade => (Family::Cascade, [160, 640]),
            };
            assert_eq!((family, out), expected, "{model}");
        }
        assert_eq!(BundledModel::from_name("paper"), None);
    }

    #[test]
    fn a_pick_choice_reads_and_writes_several_files() {
        assert_eq!(PickChoice::parse("auto"), PickChoice::Auto);
        assert_eq!(PickChoice::parse("off"), PickChoice::Off);
        assert_eq!(PickChoice::parse("chain").to_string(), "chain");
        let chain = PickChoice::Chain.load(Some(BundledModel::Cascade)).unwrap();
        assert_eq!(chain.map(|p| p.passes()), Some(2));
        // The default: the two picks; `single` the first alone.
        let auto = PickChoice::Auto.load(Some(BundledModel::Cascade)).unwrap();
        assert_eq!(auto.map(|p| p.passes()), Some(2));
        assert_eq!(PickChoice::parse("single").to_string(), "single");
        let single = PickChoice::Single
            .load(Some(BundledModel::Cascade))
            .unwrap();
        assert_eq!(single.map(|p| p.passes()), Some(1));
        assert!(
            PickChoice::Chain
                .load(Some(BundledModel::Tiny))
                .unwrap()
                .is_none()
        );
        let chain = PickChoice::parse("a.safetensors,dir/b.safetensors");
        assert_eq!(
            chain,
            PickChoice::File(vec!["a.safetensors".into(), "dir/b.safetensors".into()])
        );
        assert_eq!(chain.to_string(), "a.safetensors,dir/b.safetensors");
        // The first file that cannot be read is named.
        let err = PickChoice::parse("/nonexistent/one.safetensors,/nonexistent/two.safetensors")
            .load(None)
            .unwrap_err();
        assert!(err.to_string().contains("one.safetensors"), "{err}");
    }
}

/// Which learnt pick runs after a network (`omnimvs infer --pick`, Python's `pick=`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PickChoice {
    /// The bundled model's own picks after it: the bundled cascade's two in turn, as
    /// [`PickChoice::Chain`], none after other
    /// weights.
    Auto,
    /// No pick.
    Off,
    /// The bundled model's first pick alone, none after other
    /// weights.
    Single,
    /// The bundled model's pick and then its second pick (the bundled cascade's two),
    /// none after other weights.
    Chain,
    /// A pick's `.safetensors`, trained on the answers of the network it runs after.
    /// Several, comma-separated (`a.safetensors,b.safetensors`): each runs after the one
    /// before it.
    File(Vec<std::path::PathBuf>),
}

impl PickChoice {
    /// Reads `auto`, `off`, `single`, `chain` or a path.
    pub fn parse(text: &str) -> Self {
        match text {
            "auto" => Self::Auto,
            "off" => Self::Off,
            "single" => Self::Single,
            "chain" => Self::Chain,
            paths => Self::File(paths.split(',').map(Into::into).collect()),
        }
    }

    /// The pick this choice gives after `model` (`None`: weights that are not a bundled
    /// model's).
    ///
    /// # Errors
    /// [`NetError`] for a pick file that cannot be read or is not a pick's.
    pub fn load(&self, model: Option<BundledModel>) -> Result<Option<PickRefiner>, NetError> {
        match (self, model) {
            (Self::Single, Some(model)) => model.pick(),
            (Self::Auto | Self::Chain, Some(model)) => model.pick_chain(),
            (Self::Auto | Self::Off | Self::Single | Self::Chain, _) => Ok(None),
            (Self::File(paths), _) => {
                let mut chain: Option<PickRefiner> = None;
                for path in paths {
                    let pick = PickRefiner::load(path)?;
                    chain = Some(match chain {
                        Some(chain) => chain.followed_by(pick)?,
                        None => pick,
                    });
                }
                Ok(chain)
            }
        }
    }
}

impl std::fmt::Display for PickChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Auto => f.write_str("auto"),
            Self::Off => f.write_str("off"),
            Self::Single => f.write_str("single"),
            Self::Chain => f.write_str("chain"),
            Self::File(paths) => {
                for (i, path) in paths.iter().enumerate() {
                    write!(f, "{}{}", if i > 0 { "," } else { "" }, path.display())?;
                }
                Ok(())
            }
        }
    }
}
