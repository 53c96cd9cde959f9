//! The scene of one frame, by kind.

use crate::scene::{SceneKind, SceneSpec};
use crate::shared::GenParams;
use crate::{SynthError, house, things};

/// Generates the scene of one frame.
///
/// # Errors
/// [`SynthError::Invalid`] for [`SceneKind::Custom`] or non-positive depths.
pub fn generate(
    kind: SceneKind,
    seed: u64,
    frame: u32,
    params: &GenParams,
) -> Result<SceneSpec, SynthError> {
    if !(params.min_depth_m.is_finite() && params.min_depth_m > 0.0) {
        return Err(SynthError::invalid(
            "min depth",
            format!(
                "expected a positive number of metres, found {}",
                params.min_depth_m
            ),
        ));
    }
    match kind {
        SceneKind::Things => Ok(things::generate(seed, frame, params)),
        SceneKind::House => Ok(house::generate(seed, frame, params)),
        SceneKind::Custom => Err(SynthError::invalid(
            "scene kind",
            "custom scenes are not generated",
        )),
    }
}
