//! Scoring and output of depth methods, apart from reading datasets (`omnimvs-data`).
//!
//! * [`metrics`]: the paper's error metrics per frame and over frames, under the reference's
//!   protocol (sky not scored) and with sky; an estimate resampled to the evaluation grid.
//! * [`output`]: an estimate's files (TIFF, colour PNGs, the point cloud), reports and the
//!   evaluation of methods side by side.
//! * [`ply`]: point clouds.
//! * [`photometric`]: how well a depth map explains the images, without ground truth.
//!
//! Errors are the dataset crate's [`omnimvs_data::DataError`]: a file, a field or a size that is
//! not what was expected.

pub mod metrics;
pub mod output;
pub mod photometric;
pub mod ply;
