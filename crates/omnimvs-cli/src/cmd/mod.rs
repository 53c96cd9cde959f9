//! One module per subcommand.

pub mod bench;
pub mod demo;
pub mod eval;
pub mod finetune;
pub mod infer;
pub mod info;
pub mod lut;
pub mod pano;
pub mod parity;
pub mod rig;
pub mod sgm;
pub mod synth;
pub mod train;
