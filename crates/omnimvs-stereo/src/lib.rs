//! The classical omnidirectional stereo method of the OmniMVS paper's
//! Table 3, "ZNCC+SGM": spherical sweeping with a ZNCC matching cost,
//! regularised by semi-global matching, on a CPU.
//!
//! * [`SphericalStereo`]: the whole method for one rig, output grid and set of
//!   hypotheses; [`SphericalStereo::compute`] turns the gray images of one
//!   frame into an inverse-depth map, a fractional index map and a
//!   confidence map, with the time of each stage.
//! * [`SgmEstimator`]: the method behind the workspace's one depth interface,
//!   `omnimvs_data::DepthEstimator`, prepared for a rig, a sweep and its parameters.
//! * The sweep's geometry is `omnimvs_sweep::SphereProjector`: where each output pixel meets
//!   each sweep sphere in each camera, computed on the fly (the lookup table of all spheres
//!   would not fit the memory budget).
//! * [`Matcher::cost_volume`]: the ZNCC cost volume ([`CostVolume`], 16-bit).
//! * [`learned`]: the learned matching costs' one cost-volume driver, and the MC-CNN-style
//!   cost: per-camera feature maps from a [`FeatureExtractor`] compared by cosine similarity,
//!   in the same cost volume.
//! * [`sweepnet`]: the SweepNet-style learned cost: a network on the warped images' windows
//!   of every sphere ([`SweepCostHead`]), through the same driver.
//! * [`aggregate`]: SGM along 4 or 8 paths that wrap around in longitude.
//! * [`filter`]: median filter and confidence-based invalidation of the index map.
//! * [`winner_take_all`]: index with parabola refinement, and confidence.
//!
//! Tests and benchmarks render their scenes with `omnimvs-synth`
//! (a dev-dependency; `tests/support/scenes.rs`).
//!
//! Frames and units follow `FORMATS.md`: rig frame, inverse depth in 1/m,
//! hypothesis index `n = (N-1)(d - d_0)/(d_(N-1) - d_0)`.

mod cost;
mod error;
mod estimator;
pub mod filter;
pub mod learned;
pub mod params;
mod pipeline;
mod sgm;
pub mod sweepnet;
mod view;
mod wta;

pub use cost::{CostTimings, CostVolume, Matcher, NO_PAIR_COST, ZNCC_VARIANCE_EPS, camera_pairs};
pub use error::StereoError;
pub use estimator::SgmEstimator;
pub use learned::{FeatureExtractor, FeatureMap, feature_cost_volume};
pub use params::{
    COST_SCALE, DEFAULT_MEDIAN, DEFAULT_P1, DEFAULT_P2, Directions, SgmParams, SweepStep,
};
pub use pipeline::{LearnedCost, SphericalStereo, StageTimings, StereoResult};
pub use sgm::{AggregatedVolume, aggregate, aggregate_in};
pub use sweepnet::{Mlp, SweepCostHead};
pub use view::{CameraView, RunSampler, Taps, TexelPairs};
pub use wta::{IndexMap, winner_take_all};
