//! The stages' forward computations: group-wise correlation of the features at a stage's
//! samples, the coarse and refinement stages' scores and soft argmax, the learnt upsampling's
//! choice of centres.

use burn::tensor::Tensor;
use burn::tensor::activation::softmax;

use super::upsample::{CandidateSelector, convex_combination};
use super::{CascadeNet, StageOutput};
use crate::cascade::geometry::StageTaps;
use crate::error::NetError;

impl CascadeNet {
    /// Group-wise correlation of one stage: every camera's features `[1, C, rows, cols]`
    /// sampled at the stage's positions, then the mean product over camera pairs that see a
    /// sample, by groups of channels, and the share of cameras that see it:
    /// `[1, groups + 1, K, H, W]`.
    ///
    /// The features are gathered channels-last (`[rows * cols, C]` rows picked by the taps),
    /// so every tap reads `C` contiguous values; the camera-pair products come from two sums,
    /// `((sum f)^2 - sum f^2) / 2`, linear in the number of cameras.
    ///
    /// # Errors
    /// [`NetError::Shape`] when there are no features, their number differs from the taps'
    /// cameras, or the batch is not 1.
    pub fn correlation(
        features: &[Tensor<4>],
        taps: &StageTaps,
        groups: usize,
    ) -> Result<Tensor<5>, NetError> {
        let shape_error = |expected: Vec<usize>, actual: Vec<usize>| NetError::Shape {
            what: "feature maps of a cascade stage".into(),
            expected,
            actual,
        };
        if let Some(host) = &taps.host {
            let Some(device) = features.first().map(Tensor::device) else {
                return Err(shape_error(vec![host.cameras.len()], vec![0]));
            };
            let dims = [taps.num_hypotheses(), taps.height(), taps.width()];
            return crate::cascade::host::correlation(features, host, dims, groups, &device);
        }
        if features.is_empty() || features.len() != taps.cameras.len() {
            return Err(shape_error(vec![taps.cameras.len()], vec![features.len()]));
        }
        let [k, h, w] = [taps.num_hypotheses(), taps.height(), taps.width()];
        let mut sum: Option<Tensor<2>> = None;
        let mut sum_sq: Option<Tensor<2>> = None;
        let mut channels = 0;
        for (feature, cam) in features.iter().zip(&taps.cameras) {
            let [b, c, rows, cols] = feature.dims();
            if b != 1 {
                return Err(shape_error(vec![1, c, rows, cols], vec![b, c, rows, cols]));
            }
            channels = c;
            let table = feature.clone().reshape([c, rows * cols]).swap_dims(0, 1); // [P, C]
            let warped = gather_rows(table, cam); // [S, C]
            let sq = warped.clone().powi_scalar(2);
            sum = Some(match sum {
                Some(s) => s + warped,
                None => warped,
            });
            sum_sq = Some(match sum_sq {
                Some(s) => s + sq,
                None => sq,
            });
        }
        let (Some(sum), Some(sum_sq)) = (sum, sum_sq) else {
            return Err(shape_error(vec![1], vec![0]));
        };
        let samples = k * h * w;
        let pairs = (sum.powi_scalar(2) - sum_sq).div_scalar(2.0); // [S, C]
        let grouped = pairs
            .reshape([samples, groups, channels / groups])
            .mean_dim(2) // [S, G, 1]
            .reshape([samples, groups])
            / taps
                .pair_count
                .clone()
                .reshape([samples, 1])
                .clamp_min(1e-3); // [S, G]
        let corr = grouped
            .swap_dims(0, 1) // [G, S]
            .reshape([1, groups, k, h, w]); // [1, G, K, H, W]
        let seen = taps.visibility.clone(); // [1, 1, K, H, W]
        Ok(Tensor::cat(vec![corr, seen], 1)) // [1, G+1, K, H, W]
    }

    /// Softmax of a stage's scores and the expected index over its hypotheses
    /// `[1 or B, K, H, W]` (`N` units).
    pub fn soft_argmax(scores: Tensor<4>, hypotheses: Tensor<4>) -> StageOutput {
        let prob = softmax(scores, 1); // [B, K, H, W]
        let index = (prob.clone() * hypotheses.clone())
            .sum_dim(1)
            .squeeze_dim(1); // [B, H, W]
        StageOutput {
            prob,
            index,
            hypotheses,
        }
    }

    /// A stage's volume `[1, G + 1, K, H, W]` with the photometric cue `[1, C, K, H, W]`
    /// appended when the network has it (`[1, G + 1 + C, K, H, W]`), as it is otherwise; `C`
    /// is `channels` (2 for a coarse stage with `coarse_cue_sgm`, else 1).
    ///
    /// # Errors
    /// [`NetError::Shape`] when the network has the cue and it is missing or of another shape.
    fn with_cue(
        &self,
        volume: Tensor<5>,
        cue: Option<Tensor<5>>,
        taps: &StageTaps,
        channels: usize,
    ) -> Result<Tensor<5>, NetError> {
        if !self.config.cascade.zncc_cue {
            return Ok(volume);
        }
        let expected = [
            1,
            channels,
            taps.num_hypotheses(),
            taps.height(),
            taps.width(),
        ];
        let actual = cue.as_ref().map_or(vec![0], |c| c.dims().to_vec());
        match cue {
            Some(cue) if cue.dims() == expected => Ok(Tensor::cat(vec![volume, cue], 1)),
            _ => Err(NetError::Shape {
                what: "photometric cue of a stage (the network has `zncc_cue`)".into(),
                expected: expected.to_vec(),
                actual,
            }),
        }
    }

    /// Coarse stage from the stride-8 features of every camera and, with `zncc_cue`, the
    /// photometric cue at its samples.
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`]; a missing cue.
    pub fn coarse_stage(
        &self,
        features: &[Tensor<4>],
        taps: &StageTaps,
        cue: Option<Tensor<5>>,
    ) -> Result<StageOutput, NetError> {
        let p = &self.config.cascade;
        let volume = Self::correlation(features, taps, p.groups[2])?;
        let channels = 1 + usize::from(p.coarse_cue_sgm);
        let volume = self.with_cue(volume, cue, taps, channels)?;
        let scores = self.coarse.forward(fold_volume(volume)); // [B, K, H, W]
        Ok(Self::soft_argmax(scores, taps.hypotheses.clone()))
    }

    /// A refinement stage (`level` 1: half resolution from stride-4 features, 0: full
    /// resolution from stride-2 features).
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`].
    pub fn refine_stage(
        &self,
        level: usize,
        features: &[Tensor<4>],
        taps: &StageTaps,
    ) -> Result<StageOutput, NetError> {
        let (scores, gate) = self.refine_scores(level, features, taps)?;
        Self::gated_answer(scores, gate, taps)
    }

    /// The learnt upsampling to the grid of refinement `level` (1: half, 0: full resolution)
    /// by that grid's `selector` ([`CascadeNet::selector`]) over `taps` whose hypotheses are
    /// the candidates of every pixel ([`super::upsampling_candidates`]), with `prior` the bilinear
    /// logits ([`super::bilinear_prior`]): `[1, H, W]`, differentiable in the selector's weights.
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`].
    pub fn select_centres(
        &self,
        level: usize,
        selector: &CandidateSelector,
        features: &[Tensor<4>],
        taps: &StageTaps,
        prior: Tensor<4>,
    ) -> Result<Tensor<3>, NetError> {
        let volume = Self::correlation(features, taps, self.config.cascade.groups[level])?;
        let volume = self.with_cue(volume, taps.cue.clone(), taps, 1)?;
        let logits = selector.forward(fold_volume(volume)) + prior; // [1, 9, H, W]
        Ok(convex_combination(logits, taps.hypotheses.clone()))
    }

    /// The learnt upsampling's selector for the grid of refinement `level` (1: half, 0: full
    /// resolution), when the network has one.
    pub fn selector(&self, level: usize) -> Option<&CandidateSelector> {
        if level == 1 {
            self.up_mid.as_ref()
        } else {
            self.up_fine.as_ref()
        }
    }

    /// A refinement stage's answer from its `scores` over the hypotheses of `taps`: the soft
    /// argmax, and with a `gate`, `centre + g (soft argmax - centre)`.
    ///
    /// # Errors
    /// [`NetError::Shape`] for a gate with taps that have no centre.
    pub fn gated_answer(
        scores: Tensor<4>,
        gate: Option<Tensor<3>>,
        taps: &StageTaps,
    ) -> Result<StageOutput, NetError> {
        let mut out = Self::soft_argmax(scores, taps.hypotheses.clone());
        if let Some(gate) = gate {
            let Some(center) = taps.center.clone() else {
                return Err(NetError::Shape {
                    what: "centre of a gated refinement stage (taps without one)".into(),
                    expected: vec![1, taps.height(), taps.width()],
                    actual: vec![0],
                });
            };
            // centre + g (answer - centre): where the gate closes, the stage keeps its centre.
            out.index = center.clone() + gate * (out.index - center); // [B, H, W]
        }
        Ok(out)
    }

    /// A refinement stage's scores over its hypotheses `[B, K, H, W]` (before the soft argmax)
    /// and, when the stage has one, its gate `[B, H, W]`.
    ///
    /// # Errors
    /// See [`CascadeNet::correlation`].
    pub fn refine_scores(
        &self,
        level: usize,
        features: &[Tensor<4>],
        taps: &StageTaps,
    ) -> Result<(Tensor<4>, Option<Tensor<3>>), NetError> {
        let groups = self.config.cascade.groups[level];
        let volume = Self::correlation(features, taps, groups)?;
        let volume = self.with_cue(volume, taps.cue.clone(), taps, 1)?;
        let regularizer = if level == 1 { &self.mid } else { &self.fine };
        Ok(regularizer.forward(fold_volume(volume))) // [B, K, H, W]
    }
}

/// Bilinear sampling of a channels-last table `[P, C]` (`P = rows * cols` of a feature map)
/// at one camera's taps: `[S, C]`, `S` the taps' samples. Differentiable with respect to the
/// table (the gradient is a scatter-add).
fn gather_rows(table: Tensor<2>, taps: &crate::model::SweepTaps) -> Tensor<2> {
    let mut out: Option<Tensor<2>> = None;
    for (index, weight) in taps.indices.iter().zip(&taps.weights) {
        let samples = weight.dims()[1];
        let tap = table.clone().select(0, index.clone()) // [S, C]
            * weight.clone().reshape([samples, 1]); // [S, 1]
        out = Some(match out {
            Some(acc) => acc + tap,
            None => tap,
        });
    }
    let [_, c] = table.dims();
    out.unwrap_or_else(|| Tensor::zeros([0, c], &table.device()))
}

/// Folds a stage's volume `[B, G + 1, K, H, W]` into 2D channels `[B, (G + 1) K, H, W]`.
pub(super) fn fold_volume(volume: Tensor<5>) -> Tensor<4> {
    let [b, c, k, h, w] = volume.dims();
    volume.reshape([b, c * k, h, w])
}
