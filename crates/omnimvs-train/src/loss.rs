//! The paper's loss: the masked (and weighted) L1 distance between the predicted and the
//! ground-truth hypothesis indices, and its targets from a frame's ground truth.

use burn::tensor::{Tensor, TensorData};
use omnimvs_data::gt::GroundTruth;

/// `mean over valid pixels of |index - target|`, weighted: `index`, `target` and `mask` (1
/// for valid pixels, 0 elsewhere, or the per-pixel weights of [`target_data_with`]) are
/// `[B, H, W]`.
pub fn masked_l1(index: Tensor<3>, target: Tensor<3>, mask: Tensor<3>) -> Tensor<1> {
    let count = mask.clone().sum().clamp_min(1.0); // [1]
    ((index - target).abs() * mask).sum() / count // [1]
}

/// Rounded ground-truth indices and the valid mask as `[1, H, W]` data.
pub fn target_data(gt: &GroundTruth) -> (TensorData, TensorData) {
    target_data_with(gt, true, 1.0)
}

/// Ground-truth indices (rounded when `round`) and the per-pixel loss weights as `[1, H, W]`
/// data: 0 for invalid pixels, `sky_weight` for sky, 1 for the rest (with `sky_weight` 1, the
/// valid mask). Sky is a valid index of exactly 0, which
/// [`omnimvs_data::gt::ground_truth_index`] gives inverse depth 0 and nothing else finite:
/// every positive inverse depth lies above `d_0`. [`masked_l1`] divides by the weights' sum,
/// so it is a weighted mean.
pub fn target_data_with(
    gt: &GroundTruth,
    round: bool,
    sky_weight: f64,
) -> (TensorData, TensorData) {
    let shape = [1, gt.height, gt.width];
    let target: Vec<f32> = gt
        .index
        .iter()
        .zip(&gt.valid)
        .map(|(&n, &v)| match (v, round) {
            (false, _) => 0.0,
            (true, true) => n.round(),
            (true, false) => n,
        })
        .collect();
    let mask: Vec<f32> = gt
        .index
        .iter()
        .zip(&gt.valid)
        .map(|(&n, &v)| match (v, n == 0.0) {
            (false, _) => 0.0,
            (true, true) => sky_weight as f32,
            (true, false) => 1.0,
        })
        .collect();
    (TensorData::new(target, shape), TensorData::new(mask, shape))
}
