//! Learnt upsampling of a stage's answer to the next grid: the candidate selector, the
//! candidates' layout and the bilinear prior it starts from.

use burn::module::Module;
use burn::nn::Initializer;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::tensor::activation::softmax;
use burn::tensor::{Device, Tensor, TensorData};

use crate::config::CascadeParams;
use crate::model::blocks::ConvBn2d;

/// Candidates of a finer pixel in [`CandidateSelector`]: the 3 x 3 coarser pixels around its
/// parent.
pub const UPSAMPLE_TAPS: usize = 9;
/// Finer pixels per coarser pixel (2 x 2: each stage doubles rows and columns).
const UPSAMPLE_CHILDREN: usize = 4;
/// The starting logit of a neighbour that bilinear upsampling does not use: together such
/// taps start with under 5 % of a child's weight. Low enough to start near the bilinear
/// answer, high enough for training to reach them.
const UNUSED_TAP_LOGIT: f32 = -5.0;

/// Learnt upsampling of a stage's answer to the next grid (`convex_upsampling`): every pixel
/// of the finer grid weighs the answers of the 3 x 3 coarser pixels around its parent (its
/// candidates) by a softmax of logits that this module reads from the matching evidence at
/// each candidate (the finer stage's group-wise correlation, visibility and photometric cue
/// at the candidate's inverse depth, `[1, (G + 2) x 9, H, W]` folded), plus the logits of the
/// bilinear weights ([`bilinear_prior`]). A 3x3 convolution with ReLU (no batch norm), then
/// a 1x1 one with zero weights and biases: it starts as the bilinear resampling (within
/// the 5 % its unused taps keep).
#[derive(Module, Debug)]
pub struct CandidateSelector {
    /// 3x3 convolution (circular in longitude) with ReLU.
    pub hidden: ConvBn2d,
    /// 1x1 convolution to one logit per candidate.
    pub out: Conv2d,
}

impl CandidateSelector {
    pub(super) fn new(channels: [usize; 2], device: &Device) -> Self {
        let hidden = ConvBn2d::pano_relu(channels, device);
        let out = Conv2dConfig::new([channels[1], UPSAMPLE_TAPS], [1, 1])
            .with_initializer(Initializer::Zeros)
            .init(device);
        Self { hidden, out }
    }

    /// A new selector for the grid of refinement stage `i` (0: half, 1: full resolution) of a
    /// network with `params`: its evidence is that stage's groups, the visibility and, with the
    /// cue, the cue at each candidate; its hidden width the stage's.
    pub(super) fn for_stage(params: &CascadeParams, i: usize, device: &Device) -> Self {
        let extra = 1 + usize::from(params.zncc_cue);
        Self::new(
            [
                (params.groups[1 - i] + extra) * UPSAMPLE_TAPS,
                params.stage_channels[i],
            ],
            device,
        )
    }

    /// Its 3x3 convolution also on the host ([`ConvBn2d::with_host_conv`]).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            hidden: self.hidden.with_host_conv(),
            out: self.out,
        }
    }

    /// The candidates' evidence `[1, C, H, W]` -> logits `[1, 9, H, W]` (before the prior).
    pub fn forward(&self, evidence: Tensor<4>) -> Tensor<4> {
        self.out.forward(self.hidden.forward(evidence, None))
    }
}

/// The values of the 3 x 3 coarser pixels around each finer pixel's parent, tap by tap
/// (`[9][rows x cols.len()]`, tap `(dr + 1) x 3 + (dc + 1)` for the neighbour at `(dr, dc)`):
/// `coarse` is a `rows / 2 x width` map, the finer grid has `rows` rows and `2 width`
/// columns, of which `cols`. Rows beyond the top and bottom repeat the edge; columns wrap.
pub fn upsampling_candidates(
    coarse: &[f32],
    [coarse_rows, coarse_cols]: [usize; 2],
    cols: &std::ops::Range<usize>,
) -> Vec<f32> {
    let factor = 2;
    let rows = factor * coarse_rows;
    let n = rows * cols.len();
    let mut out = vec![0.0f32; UPSAMPLE_TAPS * n];
    for r in 0..rows {
        for (i, c) in cols.clone().enumerate() {
            let (pr, pc) = (r / factor, c / factor);
            for dr in 0..3 {
                let rr = (pr + dr).saturating_sub(1).min(coarse_rows - 1);
                for dc in 0..3 {
                    let cc = (pc + coarse_cols + dc - 1) % coarse_cols;
                    out[(dr * 3 + dc) * n + r * cols.len() + i] = coarse[rr * coarse_cols + cc];
                }
            }
        }
    }
    out
}

/// The logits of the bilinear weights (`bilinear_logits`) laid out for a finer grid of
/// `rows` rows over columns `cols`: `[1, 9, rows, cols.len()]`, each pixel its child's
/// (row and column parity).
pub fn bilinear_prior(rows: usize, cols: &std::ops::Range<usize>, device: &Device) -> Tensor<4> {
    let logits = bilinear_logits();
    let n = rows * cols.len();
    let mut out = vec![0.0f32; UPSAMPLE_TAPS * n];
    for r in 0..rows {
        for (i, c) in cols.clone().enumerate() {
            let child = (r % 2) * 2 + c % 2;
            for tap in 0..UPSAMPLE_TAPS {
                out[tap * n + r * cols.len() + i] = logits[tap * UPSAMPLE_CHILDREN + child];
            }
        }
    }
    Tensor::from_data(
        TensorData::new(out, [1, UPSAMPLE_TAPS, rows, cols.len()]),
        device,
    )
}

/// The logits whose softmax is close to the weights of the bilinear resampling of
/// [`omnimvs_sweep::resample_map`], channel `tap x 4 + child`: tap `(dr + 1) x 3 + (dc + 1)`
/// for the neighbour at `(dr, dc)`, child `a x 2 + b` for the finer pixel at row `2r + a`,
/// column `2c + b`. In longitude a finer grid's column `2c` lies on its parent and `2c + 1`
/// halfway to the next one (weights 1, and 1/2 and 1/2); in latitude the grids share their
/// first and last rows, so a child's offset from its parent drifts from 0 to half a row over
/// the grid: the start takes the middle's, a quarter row (3/4 for the parent's row, 1/4 for
/// the next one toward the child), and training corrects the rest.
fn bilinear_logits() -> [f32; UPSAMPLE_TAPS * UPSAMPLE_CHILDREN] {
    bilinear_weights().map(|w| if w > 0.0 { w.ln() } else { UNUSED_TAP_LOGIT })
}

/// The weights [`bilinear_logits`] starts near (same layout; zero for the unused taps).
fn bilinear_weights() -> [f32; UPSAMPLE_TAPS * UPSAMPLE_CHILDREN] {
    // d: 0, 1, 2 for offsets -1, 0, +1.
    let along_rows = |child: usize, d: usize| -> f32 {
        match (child, d) {
            (_, 1) => 0.75,
            (0, 0) | (1, 2) => 0.25,
            _ => 0.0,
        }
    };
    let along_cols = |child: usize, d: usize| -> f32 {
        match (child, d) {
            (0, 1) => 1.0,
            (1, 1 | 2) => 0.5,
            _ => 0.0,
        }
    };
    let mut weights = [0.0; UPSAMPLE_TAPS * UPSAMPLE_CHILDREN];
    for (tap, (dr, dc)) in (0..3)
        .flat_map(|dr| (0..3).map(move |dc| (dr, dc)))
        .enumerate()
    {
        for (child, (a, b)) in [(0, 0), (0, 1), (1, 0), (1, 1)].into_iter().enumerate() {
            weights[tap * UPSAMPLE_CHILDREN + child] = along_rows(a, dr) * along_cols(b, dc);
        }
    }
    weights
}

/// The convex combination of a stage's candidates: `softmax(logits)` over the candidates
/// `[1, K, H, W]` times their values `[1, K, H, W]`, summed: `[1, H, W]`.
pub fn convex_combination(logits: Tensor<4>, candidates: Tensor<4>) -> Tensor<3> {
    (softmax(logits, 1) * candidates).sum_dim(1).squeeze_dim(1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::read_values;
    use omnimvs_sweep::{EquirectGrid, resample_map};

    /// The learnt upsampling of a `h x w` map with the given per-child logits in place of the
    /// selector's (the bilinear prior's layout), over the finer grid's columns `cols`.
    fn upsample(
        values: &[f32],
        [h, w]: [usize; 2],
        child_logits: &[f32; 36],
        cols: std::ops::Range<usize>,
    ) -> Vec<f32> {
        let device = Device::flex();
        let n = 2 * h * cols.len();
        let candidates = upsampling_candidates(values, [h, w], &cols);
        let mut logits = vec![0.0f32; UPSAMPLE_TAPS * n];
        for r in 0..2 * h {
            for (i, c) in cols.clone().enumerate() {
                let child = (r % 2) * 2 + c % 2;
                for tap in 0..UPSAMPLE_TAPS {
                    logits[tap * n + r * cols.len() + i] = child_logits[tap * 4 + child];
                }
            }
        }
        let shape = [1, UPSAMPLE_TAPS, 2 * h, cols.len()];
        let out = convex_combination(
            Tensor::from_data(TensorData::new(logits, shape), &device),
            Tensor::from_data(TensorData::new(candidates, shape), &device),
        );
        read_values(out, "up").unwrap()
    }

    #[test]
    fn the_starting_weights_are_near_the_bilinear_resampling_along_longitude() {
        // The start puts under 5 % of every child's weight on the taps bilinear leaves out,
        // and the prior tensor lays those logits out by row and column parity.
        let start = bilinear_logits();
        let weights = bilinear_weights();
        for child in 0..UPSAMPLE_CHILDREN {
            let column = |v: &[f32; 36]| (0..9).map(|t| v[t * 4 + child]).collect::<Vec<_>>();
            let (l, w) = (column(&start), column(&weights));
            let total: f32 = l.iter().map(|x| x.exp()).sum();
            let unused: f32 = l
                .iter()
                .zip(&w)
                .filter(|(_, w)| **w == 0.0)
                .map(|(x, _)| x.exp())
                .sum();
            assert!(unused / total < 0.05, "child {child}: {}", unused / total);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
        let prior = read_values(bilinear_prior(4, &(3..7), &Device::flex()), "prior").unwrap();
        assert_eq!(prior.len(), 9 * 4 * 4);
        // Tap 4 (the parent) of the pixel at row 1, column 4 (child (1, 0)): ln(3/4 x 1).
        assert!((prior[4 * 16 + 4 + 1] - 0.75f32.ln()).abs() < 1e-6);
        // Those weights, sharpened, on a map that varies along columns only: `resample_map`
        // exactly, the wrap-around included (the last child column lies halfway to the first).
        let sharp = weights.map(|w| if w > 0.0 { w.ln() } else { -60.0 });
        let (h, w) = (4, 8);
        let values: Vec<f32> = (0..h * w).map(|i| ((i % w) * (i % w)) as f32).collect();
        let up = upsample(&values, [h, w], &sharp, 0..2 * w);
        let from = EquirectGrid::new(h, w, 45.0).unwrap();
        let to = EquirectGrid::new(2 * h, 2 * w, 45.0).unwrap();
        let expected = resample_map(&values, &from, &to);
        for (a, b) in up.iter().zip(&expected) {
            assert!((a - b).abs() < 1e-3, "{a} vs {b}");
        }
        // Along rows, a quarter row toward each child: 3/4 and 1/4; the edges repeat.
        let values: Vec<f32> = (0..h * w).map(|i| 10.0 * (i / w) as f32).collect();
        let up = upsample(&values, [h, w], &sharp, 0..2 * w);
        let at = |r: usize| up[r * 2 * w];
        assert!((at(2) - 7.5).abs() < 1e-3 && (at(3) - 12.5).abs() < 1e-3);
        assert!(at(0).abs() < 1e-3 && (at(2 * h - 1) - 30.0).abs() < 1e-3);
    }

    #[test]
    fn sharp_weights_take_one_neighbour_in_a_window_and_around_the_seam() {
        // All weight on the neighbour to the right (tap (0, +1) = 5): every child takes it,
        // the last columns the first coarse column's (the panorama wraps).
        let (h, w) = (3, 5);
        let values: Vec<f32> = (0..h * w).map(|i| (10 * (i / w) + i % w) as f32).collect();
        let mut sharp = [-30.0f32; 36];
        for child in 0..4 {
            sharp[5 * 4 + child] = 30.0;
        }
        let cols = 6..2 * w;
        let up = upsample(&values, [h, w], &sharp, cols.clone());
        for r in 0..2 * h {
            for (i, c) in cols.clone().enumerate() {
                let right = values[(r / 2) * w + (c / 2 + 1) % w];
                assert!((up[r * cols.len() + i] - right).abs() < 1e-4);
            }
        }
    }
}
