//! Dataset folders in the reference OmniMVS layout (`FORMATS.md`).
//!
//! * [`Dataset`]: `config.yaml` (rig, min depth, `img_fmt`, frame range),
//!   frame files by index, validity masks.
//! * [`image_io`]: gray images (RGB -> channel mean), the network's input
//!   normalisation, PNG writing.
//! * [`gt`]: ground-truth inverse depth in its three encodings, cropping and
//!   the invalid-pixel rule; the f32 TIFF writer.
//! * [`metrics`]: the paper's error metrics per frame and over frames.
//! * [`colormap`], [`ply`]: pictures and point clouds of results; [`edges`]: depth edges
//!   without blends (no points floating between two surfaces).
//! * [`estimate`]: [`DepthEstimator`], the one interface of every depth method, and its
//!   [`DepthEstimate`].
//! * [`output`]: an estimate's files, reports and the evaluation of methods side by side.

pub mod colormap;
mod config;
mod dataset;
pub mod edges;
mod error;
pub mod estimate;
mod format;
pub mod gt;
pub mod image_io;
pub mod metrics;
pub mod output;
pub mod ply;

pub use config::{DatasetConfig, FrameRange, Split, write_config_yaml};
pub use dataset::{Dataset, RELEASED_MAX_FOV_DEG, RELEASED_MIN_DEPTH_M};
pub use error::DataError;
pub use estimate::{
    DepthEstimate, DepthEstimator, EstimateError, Finishing, FinishingError, NoTimings,
    StageObserver, StageTimes, Uncertainty,
};
pub use format::format_printf;
