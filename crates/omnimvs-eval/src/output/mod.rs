//! Everything a run writes and reports, for the command line and the bindings alike:
//!
//! * [`files`]: one frame's estimate as files (`%05d.tiff`, `_index.tiff`, confidence or
//!   entropy, colour maps, the `_vis.png` composite, the point cloud).
//! * [`pictures`]: the building blocks of those pictures (RGB8 rows).
//! * [`report`]: Markdown tables of both protocols, `sgm.json`, `metrics.json`, atomic JSON
//!   and text writes.
//! * [`runs`]: a method's outputs over a dataset's frames (`omnimvs sgm`'s and
//!   `omnimvs infer`'s layouts).
//! * [`evaluation`]: methods scored at one evaluation sweep, `eval.json` and `eval.md`.
//!
//! Every file goes through `omnimvs_core::fs::write_atomic`.

pub mod evaluation;
pub mod files;
pub mod pictures;
pub mod report;
pub mod runs;

pub use evaluation::{EvalReport, Evaluation, MethodResult, MethodScores};
pub use files::{FrameScene, frame_path, write_depth_pictures, write_maps, write_percentile_png};
pub use report::{protocol_tables, write_json, write_text};
pub use runs::{ConfidenceRun, DepthRun};
