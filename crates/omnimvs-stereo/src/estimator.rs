//! The classical method behind the workspace's one depth interface, [`DepthEstimator`].

use std::sync::Arc;

use omnimvs_camera::{Rig, ValidityMask};
use omnimvs_core::GrayImage;
use omnimvs_data::{DepthEstimate, DepthEstimator, EstimateError, StageObserver};
use omnimvs_sweep::SweepSpec;

use crate::{FeatureExtractor, LearnedCost, SgmParams, SphericalStereo, StageTimings, StereoError};

/// ZNCC (or a learned cost, [`Self::with_features`]) + SGM prepared for one rig, sweep and set of parameters, with the cameras' validity
/// masks (pixels marked invalid are never sampled).
#[derive(Debug, Clone)]
pub struct SgmEstimator {
    stereo: SphericalStereo,
    spec: SweepSpec,
    masks: Option<Vec<ValidityMask>>,
}

impl SgmEstimator {
    /// The method's name in reports.
    pub const NAME: &'static str = "ZNCC+SGM";

    /// # Errors
    /// As [`SphericalStereo::new`]; [`StereoError::CountMismatch`] for another number of
    /// masks than cameras.
    pub fn new(
        rig: &Rig,
        masks: Option<Vec<ValidityMask>>,
        spec: SweepSpec,
        params: SgmParams,
    ) -> Result<Self, StereoError> {
        if let Some(m) = &masks
            && m.len() != rig.len()
        {
            return Err(StereoError::CountMismatch {
                what: "validity masks",
                expected: rig.len(),
                found: m.len(),
            });
        }
        let stereo = SphericalStereo::new(rig, spec.grid, spec.hypotheses, params)?;
        Ok(Self {
            stereo,
            spec,
            masks,
        })
    }

    /// The same method with a learned matching cost (`None`: ZNCC); its name becomes the
    /// extractor's (`MC-CNN+SGM`).
    pub fn with_features(mut self, extractor: Option<Arc<dyn FeatureExtractor>>) -> Self {
        self.stereo = self.stereo.with_features(extractor);
        self
    }

    /// The same method with any learned matching cost (`None`: ZNCC); its name becomes the
    /// cost's (`MC-CNN+SGM`, `SweepNet+SGM`).
    pub fn with_learned_cost(mut self, learned: Option<LearnedCost>) -> Self {
        self.stereo = self.stereo.with_learned_cost(learned);
        self
    }

    /// The method's parameters.
    pub fn params(&self) -> &SgmParams {
        &self.stereo.params
    }
}

impl StageTimings {
    /// Gives every stage to `observer`, `total` last.
    pub fn report(&self, observer: &mut dyn StageObserver) {
        observer.stages(&[
            ("prepare", self.prepare_s),
            ("warp", self.warp_s),
            ("cost", self.cost_s),
            ("aggregation", self.aggregation_s),
            ("wta", self.wta_s),
            ("total", self.total_s),
        ]);
    }
}

impl From<StereoError> for EstimateError {
    fn from(e: StereoError) -> Self {
        Self::new(e)
    }
}

impl DepthEstimator for SgmEstimator {
    fn name(&self) -> &str {
        self.stereo
            .learned_cost()
            .map_or(Self::NAME, LearnedCost::method_name)
    }

    fn spec(&self) -> &SweepSpec {
        &self.spec
    }

    /// The stages are timed in any case (the clock costs nothing next to them).
    fn estimate_observed(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
    ) -> Result<DepthEstimate, EstimateError> {
        let out = self.stereo.compute(images, self.masks.as_deref())?;
        out.timings.report(observer);
        Ok(DepthEstimate {
            spec: self.spec,
            method: self.name().into(),
            inv_depth: out.inv_depth,
            index: out.index.index,
            confidence: Some(out.index.confidence),
            entropy: None,
            spread: None,
            seconds: out.timings.total_s,
        })
    }
}
