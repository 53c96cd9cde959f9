//! Synthetic omnidirectional stereo datasets (OmniThings / OmniHouse style)
//! for any rig of fisheye cameras.
//!
//! * [`things::generate`] and [`house::generate`] make a [`SceneSpec`]
//!   deterministically from a seed and a frame index.
//! * [`Tracer`] puts the scene in the rig frame under a BVH and shades rays.
//! * [`render_fisheye`] renders one camera through its exact model;
//!   [`render_inverse_depth`] the ground truth on the equirectangular grid.
//!
//! Frames: the rig frame of `FORMATS.md` (x right, y down, z forward);
//! scenes are built in a "world" frame with the same axes (y down) and the
//! rig placed in it by [`SceneSpec::world_from_rig`]. Distances in metres,
//! inverse depths in 1/m.

pub mod camera_effects;
pub mod contact;
pub mod dataset;
mod difficulty;
mod error;
pub mod generate;
pub mod house;
pub mod mesh;
pub mod mesh_file;
pub mod primitive;
pub mod random_rig;
pub mod render;
pub mod rig;
pub mod rng;
pub mod scene;
mod shared;
pub mod split;
pub mod texture;
pub mod things;
mod tracer;

pub use camera_effects::CameraEffects;
pub use dataset::{DatasetWriter, Frame, FrameEvent, Shard, SynthOptions, SynthSettings};
pub use difficulty::Difficulty;
pub use error::SynthError;
pub use generate::generate;
pub use render::{
    render_fisheye, render_fisheye_into, render_gray_frame, render_inverse_depth,
    render_inverse_depth_map,
};
pub use scene::{LightSpec, ObjectSpec, Placement, SceneKind, SceneSpec, ShapeSpec, SkySpec};
pub use shared::GenParams;
pub use tracer::{Hit, MeshLibrary, Tracer};
