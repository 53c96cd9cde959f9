//! The OmniMVS network (Won, Ryu and Lim, ICCV 2019) in burn.
//!
//! Fisheye images pass one by one through the unary feature CNN, are warped onto `N / 2`
//! spheres around the rig through a precomputed lookup table ([`taps`]), transferred by a
//! stride-2 convolution, concatenated over cameras, fused and regularised by a 3D
//! encoder-decoder; a softargmin over the `N` hypotheses gives the inverse-depth index.
//!
//! - [`config`]: sizes, layouts (ICCV paper / published weights) and presets.
//! - [`model`]: the burn modules, named like the reference PyTorch state dict.
//! - [`cascade`]: the coarse-to-fine network for CPUs at the paper's output grid; its burn
//!   modules in `cascade::model`, one file per stage.
//! - [`pick`]: the learnt pick after the cascade, on the host.
//! - [`taps`]: bilinear taps of a lookup table and the host warp kernel.
//! - [`weights`]: our safetensors files and the import of reference PyTorch checkpoints.
//! - [`infer`]: running the paper's network on a dataset's frames.
//! - [`estimator`]: either family on a dataset's frames, one result type; composes the
//!   cascade and the pick after it ([`estimator::PickedCascade`]).
//! - [`mccnn`]: the MC-CNN-style matching-cost network for `omnimvs-stereo`'s SGM.
//! - [`learned_sgm`]: SGM on ZNCC or a learned cost, by name.
//! - [`sweepnet`]: the SweepNet-style matching-cost head for `omnimvs-stereo`'s SGM.
//! - [`synthetic`]: a lookup table without a rig, for benchmarks and tests.
//! - [`hostconv`]: 2D and 3D convolutions on the host for inference on a CPU (burn flex).
//! - [`backend`]: run-time choice of the compute backend (`cpu`, `libtorch`, `wgpu`, ...).
//! - [`pixel`]: per-pixel projection into the cameras and window sums on the panorama,
//!   shared by the cascade and the pick.
//! - [`tensor`]: generic helpers on tensors (values read back to the host).
//!
//! Imports run one way: [`tensor`], [`error`], [`taps`] and [`pixel`] import nothing above
//! them; [`cascade`] and [`pick`] do not import each other; [`estimator`] composes them.
//!
//! Training is the crate `omnimvs-train`; the benchmarks of `omnimvs bench` are the CLI's.

pub mod backend;
pub mod bundled;
pub mod cascade;
pub mod config;
pub mod error;
pub mod estimator;
pub mod hostconv;
pub mod infer;
pub mod learned_sgm;
pub mod mccnn;
pub mod model;
pub mod pick;
pub mod pixel;
pub mod sweepnet;
pub mod synthetic;
pub mod taps;
pub mod tensor;
pub mod weights;

pub use backend::Backend;
pub use bundled::BundledModel;
pub use cascade::CascadeNet;
pub use config::{CascadeParams, Family, Layout, NetConfig};
pub use error::NetError;
pub use estimator::NetEstimator;
pub use model::{NetOutput, OmniMvsNet, SweepInput, SweepTaps};
pub use taps::SweepGrid;
