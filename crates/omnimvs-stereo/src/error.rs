use omnimvs_data::DataError;
use omnimvs_sweep::SweepError;

/// Errors of the stereo crate; each says which input is wrong and what was
/// expected.
#[derive(Debug, thiserror::Error)]
pub enum StereoError {
    #[error(transparent)]
    Sweep(#[from] SweepError),
    #[error(transparent)]
    Data(#[from] DataError),
    #[error("rig has {found} camera(s): stereo needs at least two")]
    TooFewCameras { found: usize },
    #[error("{what}: {found} given for a rig of {expected} cameras")]
    CountMismatch {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    #[error(
        "camera {camera} {what} is {found_w}x{found_h} (width x height), \
         expected {want_w}x{want_h} (the camera's image_size)"
    )]
    SizeMismatch {
        /// 1-based camera number.
        camera: usize,
        what: &'static str,
        found_w: usize,
        found_h: usize,
        want_w: usize,
        want_h: usize,
    },
    #[error("ndepth {found}: expected an even number of at least 2 inverse-depth hypotheses")]
    NDepth { found: usize },
    #[error("SGM parameter {name} = {value}: expected {expected}")]
    Parameter {
        name: &'static str,
        value: String,
        expected: &'static str,
    },
    #[error("SGM penalties P1 = {p1}, P2 = {p2}: {reason}")]
    Penalties { p1: f32, p2: f32, reason: String },
    #[error("cost volume: {0}")]
    Volume(String),
}
