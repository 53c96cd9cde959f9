//! A coarse-to-fine network for accuracy per CPU-second at the paper's output grid
//! (`160 x 640`, `N = 192`), in the spirit of CasMVSNet (Gu et al., CVPR 2020) with
//! GwcNet's group-wise correlation:
//!
//! 1. a feature pyramid of every fisheye image at strides 2, 4 and 8;
//! 2. a coarse cost volume at a quarter of the output (`40 x 160`) over 32 spheres through
//!    the whole inverse-depth range, built by group-wise correlation across the cameras that
//!    see each sample (not concatenation: the volume stays small and the camera order does
//!    not matter), regularised by a two-level 2D encoder-decoder whose input channels are
//!    (groups x spheres), soft argmax;
//! 3. at half (`80 x 320`) and full resolution, a few hypotheses per pixel around the
//!    previous estimate, sampled through the camera model at per-pixel inverse depths
//!    ([`crate::pixel::PixelSampler`]), correlated and scored by three 2D convolutions over
//!    (groups x hypotheses) channels, soft argmax.
//!
//! Every convolution on the panorama wraps around in longitude. See `crates/omnimvs-net/README.md` for the
//! design choices, FLOPs, time and memory per stage.
//!
//! - [`sampler`]: hypothesis placement: the coarse spheres, a refinement stage's hypotheses
//!   around each pixel's estimate.
//! - [`geometry`]: a stage's taps on the device, a rig's geometry, the forward pass.
//! - [`host`]: the correlation of a stage on the host, for inference on a CPU.
//! - [`model`]: the burn modules.
//! - [`photo`]: the photometric cue (`zncc_cue`), ZNCC of the cameras' own images at a
//!   stage's samples, one more channel of its volume.
//! - [`infer`]: the network on a dataset's frames.

pub mod geometry;
pub mod host;
pub mod infer;
pub mod model;
pub mod photo;
pub mod sampler;

pub use crate::pixel::PixelSampler;
pub use geometry::{
    CascadeGeometry, CascadeOutput, CascadeTimings, ColumnWindow, HostTaps, SeedChoice, StageTaps,
};
pub use infer::{CascadeAnswer, CascadeInference};
pub use model::{CascadeNet, StageOutput};
