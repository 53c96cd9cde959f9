//! One module per subcommand.

pub mod eval;
pub mod info;
pub mod lut;
pub mod pano;
pub mod synth;
pub mod train;
