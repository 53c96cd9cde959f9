use std::path::PathBuf;

/// Errors of the sweep crate.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("invalid equirectangular grid: {0}")]
    Grid(String),
    #[error("invalid inverse-depth hypotheses: {0}")]
    Hypotheses(String),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{path}: lookup table file has {found} bytes, expected {expected} \
         ({cameras} cameras x {spheres} spheres x {height}x{width} x 2 f32)"
    )]
    HwdSize {
        path: PathBuf,
        found: u64,
        expected: u64,
        cameras: usize,
        spheres: usize,
        height: usize,
        width: usize,
    },
    #[error("camera {camera}: {reason}")]
    Camera { camera: usize, reason: String },
    #[error("{what}: expected {expected}, found {found}")]
    Mismatch {
        what: String,
        expected: String,
        found: String,
    },
}

impl SweepError {
    /// `what` was expected to be `expected` and was `found`: a size or count that does not
    /// fit (also what the data crate reports for its own mismatches).
    pub fn mismatch(
        what: impl Into<String>,
        expected: impl ToString,
        found: impl ToString,
    ) -> Self {
        Self::Mismatch {
            what: what.into(),
            expected: expected.to_string(),
            found: found.to_string(),
        }
    }
}
