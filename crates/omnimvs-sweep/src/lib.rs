//! Spherical sweeping (paper section 3.1, `FORMATS.md`).
//!
//! * [`EquirectGrid`]: the equirectangular output grid and its unit rays in
//!   the rig frame.
//! * [`InvDepthHypotheses`]: `N` spheres evenly spaced in inverse depth, and
//!   index <-> inverse depth conversions.
//! * [`LookupTable`]: for every camera, sphere and grid pixel, where to sample
//!   the fisheye image, in the reference `lt_(h,w,N).hwd` layout; built in
//!   parallel and cached per rig ([`LutCache`]).
//! * [`warp`]: bilinear warping of `C x H x W` maps onto the spheres with
//!   `grid_sample(align_corners=True)` semantics and zeros outside.
//! * [`panorama`]: the gray or colour panorama composed from all cameras at a given
//!   inverse depth.
//! * [`SweepSpec`]: a grid and its hypotheses, what every depth estimate answers on.
//! * [`resample_map`]: a map carried from one grid to another of the same
//!   latitudes (bilinear, longitude wrapping around).

mod cache;
mod error;
mod grid;
mod hugepages;
mod hypotheses;
mod lut;
pub mod panorama;
mod projector;
mod resample;
mod spec;
pub mod warp;

pub use cache::{CacheStatus, LutCache};
pub use error::SweepError;
pub use grid::EquirectGrid;
pub use hypotheses::InvDepthHypotheses;
pub use lut::{
    INVALID_PIXEL, LookupTable, SphereSet, hwd_file_name, normalized_pixel, normalized_position,
};
pub use panorama::{
    ColourPanorama, InvDepthSource, Panorama, compose_colour_panorama, compose_panorama,
    warp_camera_to_panorama,
};
pub use projector::SphereProjector;
pub use resample::resample_map;
pub use spec::SweepSpec;
pub use warp::warp_camera_onto_spheres;
