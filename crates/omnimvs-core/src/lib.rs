//! What every omnimvs crate shares, and nothing else: the lowest crate of the workspace.
//!
//! * [`fs`]: atomic file writes (temporary file, then rename); `clippy.toml` disallows
//!   `std::fs::write` and `File::create` everywhere else.
//! * [`rng`]: the one seeded generator (SplitMix64).
//! * [`yaml`]: parse once, deserialise with the path of the failing field, write in the
//!   reference's layout.
//! * [`GrayImage`]: the single-channel f32 image every stage passes along; [`ColourPlanes`]:
//!   three of them, the colour of images, panoramas and point clouds.
//! * [`interp`]: bilinear sampling, the one home of every bilinear read and resize.
//! * [`safetensors`]: the one safetensors reader for weights read outside burn's records.

mod colour;
pub mod fs;
mod image;
pub mod interp;
pub mod rng;
pub mod safetensors;
pub mod yaml;

pub use colour::ColourPlanes;
pub use image::GrayImage;
