//! Dataset folders in the reference OmniMVS layout (`FORMATS.md`) and the one interface of
//! every depth method; scoring and output files are `omnimvs-eval`'s.
//!
//! * [`Dataset`]: `config.yaml` (rig, min depth, `img_fmt`, frame range),
//!   frame files by index, validity masks.
//! * [`image_io`]: gray images (RGB -> channel mean) and, for panoramas and point clouds,
//!   colour ones; the network's input normalisation, PNG writing.
//! * [`gt`]: ground-truth inverse depth in its three encodings, cropping and
//!   the invalid-pixel rule; the f32 TIFF writer.
//! * [`colormap`]: colour maps of inverse depth (the ground truth's picture page and every
//!   output picture); [`edges`]: depth edges without blends (no points floating between two
//!   surfaces).
//! * [`estimate`]: [`DepthEstimator`], the one interface of every depth method, and its
//!   [`DepthEstimate`].

pub mod colormap;
mod config;
mod dataset;
pub mod edges;
mod error;
pub mod estimate;
mod format;
pub mod gt;
pub mod image_io;
pub mod layout;
mod open;
pub mod speed;

pub use config::{DatasetConfig, FrameRange, Split, write_config_yaml};
pub use dataset::Dataset;
pub use error::DataError;
pub use estimate::{
    DepthEstimate, DepthEstimator, EstimateError, Finishing, FinishingError, NoTimings,
    StageObserver, StageTimes, Uncertainty,
};
pub use format::format_printf;
pub use open::{Found, OpenOptions, RELEASED_MAX_FOV_DEG, RELEASED_MIN_DEPTH_M, RigFrame};
pub use speed::Speed;
