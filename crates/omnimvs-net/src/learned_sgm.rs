//! SGM on any matching cost of the paper's comparison table, ready to run: ZNCC, the
//! MC-CNN-style cost ([`crate::mccnn`]) or the SweepNet-style cost ([`crate::sweepnet`]),
//! with the learned cost's weights by name. What `omnimvs sgm --cost`, `omnimvs eval
//! --method` and the Python package's `sgm(cost=)` share.

use std::str::FromStr;

use burn::tensor::Device;
use omnimvs_camera::{Rig, ValidityMask};
use omnimvs_stereo::{DEFAULT_P1, DEFAULT_P2, SgmEstimator, SgmParams};
use omnimvs_sweep::SweepSpec;

use crate::error::NetError;

/// The matching cost that SGM regularises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatchingCost {
    /// 9x9 ZNCC over every camera pair (the paper's ZNCC+SGM).
    Zncc,
    /// The MC-CNN-style learned cost.
    McCnn,
    /// The SweepNet-style learned cost.
    SweepNet,
}

impl MatchingCost {
    /// The names [`FromStr`] takes.
    pub const NAMES: [&'static str; 3] = ["zncc", "mccnn", "sweepnet"];
}

impl FromStr for MatchingCost {
    type Err = NetError;

    fn from_str(s: &str) -> Result<Self, NetError> {
        match s {
            "zncc" => Ok(Self::Zncc),
            "mccnn" => Ok(Self::McCnn),
            "sweepnet" => Ok(Self::SweepNet),
            other => Err(NetError::InvalidConfig {
                field: "cost",
                message: format!("{other:?}: expected one of {:?}", Self::NAMES),
            }),
        }
    }
}

/// SGM on `cost` for a rig: a learned cost's network from `weights` (`bundled`, `random` or
/// a `.safetensors` file) on the CPU; `params` gets the cost's own default penalties
/// `(P1, P2)` and gives the method's parameters (the SweepNet cost sets its window size).
///
/// # Errors
/// [`NetError`] for unloadable weights or a rig, masks or sweep that do not fit.
pub fn sgm_estimator(
    rig: &Rig,
    masks: Vec<ValidityMask>,
    spec: SweepSpec,
    cost: MatchingCost,
    weights: &str,
    params: impl Fn((f32, f32)) -> SgmParams,
) -> Result<SgmEstimator, NetError> {
    let device = Device::flex();
    match cost {
        MatchingCost::Zncc => Ok(SgmEstimator::new(
            rig,
            Some(masks),
            spec,
            params((DEFAULT_P1, DEFAULT_P2)),
        )?),
        MatchingCost::McCnn => {
            let net = crate::mccnn::from_name(weights, &device)?;
            let p = params((net.config.p1, net.config.p2));
            let extractor = crate::mccnn::McCnnExtractor {
                net,
                masks: Some(masks.clone()),
                device,
            };
            Ok(SgmEstimator::new(rig, Some(masks), spec, p)?
                .with_features(Some(extractor.shared())))
        }
        MatchingCost::SweepNet => {
            let net = crate::sweepnet::from_name(weights, &device)?;
            let p = SgmParams {
                patch: 2 * net.config.radii.iter().copied().max().unwrap_or(4) + 1,
                ..params((net.config.p1, net.config.p2))
            };
            Ok(SgmEstimator::new(rig, Some(masks), spec, p)?
                .with_learned_cost(Some(net.learned_cost()?)))
        }
    }
}
