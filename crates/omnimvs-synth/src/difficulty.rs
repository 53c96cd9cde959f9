//! How hard a generated dataset is for stereo matching.

use serde::{Deserialize, Serialize};

use crate::SynthError;

/// How hard the generated scenes and images are.
///
/// * `Standard`: the generator as it always was (rich procedural textures,
///   mostly convex shapes, even lighting, ideal cameras); a seed gives the
///   same bytes as before this option existed.
/// * `Hard`: where the paper's OmniThings and real rigs are hard: flat,
///   low-contrast, repetitive and dark textures; thin and concave shapes
///   (rods, plates, rings, frames and plates with holes, lattices, tubes);
///   several point lights with strong falloff in darker scenes; and per
///   camera and frame real-camera effects on the 8-bit images (gain and
///   exposure, gamma, vignetting, blur, sensor noise: see
///   [`crate::camera_effects`]). The ground truth stays exact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Difficulty {
    #[default]
    Standard,
    Hard,
}

impl Difficulty {
    pub fn name(self) -> &'static str {
        match self {
            Self::Standard => "standard",
            Self::Hard => "hard",
        }
    }

    pub fn is_hard(self) -> bool {
        self == Self::Hard
    }
}

impl std::str::FromStr for Difficulty {
    type Err = SynthError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "standard" => Ok(Self::Standard),
            "hard" => Ok(Self::Hard),
            _ => Err(SynthError::invalid(
                "difficulty",
                format!("unknown difficulty {s:?}, expected \"standard\" or \"hard\""),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_standard_is_the_default() {
        for d in [Difficulty::Standard, Difficulty::Hard] {
            assert_eq!(d.name().parse::<Difficulty>().ok(), Some(d));
            assert_eq!(
                serde_json::to_string(&d).ok(),
                Some(format!("\"{}\"", d.name()))
            );
        }
        assert_eq!(Difficulty::default(), Difficulty::Standard);
        assert!("medium".parse::<Difficulty>().is_err());
    }
}
