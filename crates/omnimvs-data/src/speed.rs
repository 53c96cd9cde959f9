//! Speed presets: how fast a method answers, traded against how well, the same for the
//! command line (`--speed` of `sgm` and `infer`) and Python (`speed=`).

/// A speed preset. Every preset answers on the paper's 160x640 grid; the README's
/// speed/accuracy table scores each on the held-out sets beside its frames per second.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Speed {
    /// ZNCC+SGM over 32 spheres; the bundled network at half its input size, without its
    /// learnt picks.
    Fast,
    /// ZNCC+SGM over 64 spheres; the bundled network without its learnt picks.
    Balanced,
    /// The paper's ZNCC+SGM (192 spheres); the bundled network with its learnt picks: the
    /// defaults.
    Accurate,
}

impl Speed {
    /// Every preset, fastest first.
    pub const ALL: [Self; 3] = [Self::Fast, Self::Balanced, Self::Accurate];

    /// The preset's name on the command line and in Python.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fast => "fast",
            Self::Balanced => "balanced",
            Self::Accurate => "accurate",
        }
    }

    /// The number of spheres (inverse-depth hypotheses) ZNCC+SGM matches over.
    pub fn sgm_ndepth(self) -> usize {
        match self {
            Self::Fast => 32,
            Self::Balanced => 64,
            Self::Accurate => 192,
        }
    }

    /// Whether the bundled network's learnt picks run after it.
    pub fn net_picks(self) -> bool {
        self == Self::Accurate
    }

    /// The network's input size for a model trained at `model_size`: half of it in each
    /// direction for `fast`, the model's own otherwise.
    pub fn net_input_size(self, model_size: [usize; 2]) -> [usize; 2] {
        match self {
            Self::Fast => model_size.map(|v| v.div_ceil(2).max(2)),
            Self::Balanced | Self::Accurate => model_size,
        }
    }
}

impl std::str::FromStr for Speed {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|s| s.name() == text)
            .ok_or_else(|| format!("expected fast, balanced or accurate, found {text:?}"))
    }
}

impl std::fmt::Display for Speed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_read_their_names_and_order_their_work() {
        for speed in Speed::ALL {
            assert_eq!(speed.name().parse::<Speed>(), Ok(speed));
        }
        assert!("quick".parse::<Speed>().is_err());
        let n: Vec<usize> = Speed::ALL.iter().map(|s| s.sgm_ndepth()).collect();
        assert!(n.windows(2).all(|w| w[0] < w[1]), "{n:?}");
        assert_eq!(Speed::Fast.net_input_size([768, 800]), [384, 400]);
        assert_eq!(Speed::Accurate.net_input_size([768, 800]), [768, 800]);
        assert!(Speed::Accurate.net_picks() && !Speed::Balanced.net_picks());
    }
}
