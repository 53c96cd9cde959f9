//! Network modules: blocks, unary features, spherical sweep, cost volume, softargmin.

pub mod blocks;
pub mod cost;
pub mod feature;
pub mod net;
pub mod softargmin;
pub mod sweep;

pub use cost::CostCompute;
pub use feature::FeatureLayers;
pub use net::{DEFAULT_SWEEP_CHUNK, NetOutput, OmniMvsNet, StageTimings, SweepInput};
pub use sweep::{SphericalSweep, SweepTaps};
