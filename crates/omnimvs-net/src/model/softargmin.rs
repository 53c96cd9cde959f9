//! Softargmin over the inverse-depth hypotheses and the entropy of the distribution.

use burn::tensor::activation::softmax;
use burn::tensor::{Int, Tensor};

/// Per-pixel probability over the `N` hypotheses: `softmax(cost)` along dim 1.
///
/// The reference implementation (and its published weights) applies the softmax to the cost
/// volume as is, not to its negation as the paper's equation reads: the network simply learns
/// the opposite sign.
pub fn probability(cost: Tensor<4>) -> Tensor<4> {
    softmax(cost, 1) // [B, N, H, W]
}

/// Expected hypothesis index `sum_n n p_n`: `[B, N, H, W] -> [B, H, W]`, in `[0, N - 1]`.
pub fn expected_index(prob: Tensor<4>) -> Tensor<3> {
    let [_, n, _, _] = prob.dims();
    let device = prob.device();
    let indices = Tensor::<1, Int>::arange(0..n as i64, &device)
        .float()
        .reshape([1, n, 1, 1]); // [1, N, 1, 1]
    (prob * indices).sum_dim(1).squeeze_dim(1) // [B, H, W]
}

/// Entropy `-sum_n p_n ln(p_n + eps)` of the per-pixel distribution (nats), `eps` the
/// `f64` machine epsilon as in the reference: `[B, N, H, W] -> [B, H, W]`.
pub fn entropy(prob: Tensor<4>) -> Tensor<3> {
    let log = prob.clone().add_scalar(f64::EPSILON).log(); // [B, N, H, W]
    (prob * log).sum_dim(1).squeeze_dim(1).neg() // [B, H, W]
}
