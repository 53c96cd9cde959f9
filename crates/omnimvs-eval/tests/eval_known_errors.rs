#![allow(clippy::unwrap_used)]
//! `eval`'s figures against hand-made predictions, whose errors are known in advance: the
//! ground truth itself scores 0; the ground truth shifted by `k` indices scores `E = k / N * 100`
//! at every pixel, so MAE = RMS = E and the `> 1, 3, 5` columns are 0 or 100; half the pixels
//! shifted halves MAE; non-finite predictions are not scored; the reference protocol leaves
//! sky out and `with-sky` scores it; a coarser prediction resampled to the evaluation grid
//! keeps a constant answer. The scoring path is the one `omnimvs eval` runs
//! (`eval_truth_on_grid`, `index_on_eval_grid`, `eval_metrics`, `ProtocolMetrics::mean`).

use omnimvs_data::gt::{EvalTruth, InvDepthMap, eval_truth_on_grid};
use omnimvs_eval::metrics::{Metrics, ProtocolMetrics, eval_metrics, index_on_eval_grid};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};

const N: usize = 50;
/// Rows of the 320-row ground truth that are sky: rows 20..50 of the 160-row crop.
const SKY_ROWS: std::ops::Range<usize> = 100..130;

fn hyps() -> InvDepthHypotheses {
    InvDepthHypotheses::new(N, 1.0).unwrap()
}

/// A full-sphere 320x640 ground truth: a band of sky, elsewhere the hypothesis of index
/// `index(col)`.
fn ground_truth(index: impl Fn(usize) -> f64) -> InvDepthMap {
    let hyps = hyps();
    let (width, height) = (640, 320);
    let mut data = Vec::with_capacity(width * height);
    for row in 0..height {
        for col in 0..width {
            data.push(if SKY_ROWS.contains(&row) {
                0.0
            } else {
                hyps.inv_depth(index(col)) as f32
            });
        }
    }
    InvDepthMap {
        width,
        height,
        data,
    }
}

/// The evaluation grid of the paper, 160x640 over +-45 degrees (the middle rows of the map).
fn eval_grid() -> EquirectGrid {
    EquirectGrid::new(160, 640, 45.0).unwrap()
}

fn truth() -> EvalTruth {
    eval_truth_on_grid(
        &ground_truth(|col| 5.0 + (col % 40) as f64),
        &hyps(),
        &eval_grid(),
    )
    .unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

fn assert_metrics(m: &Metrics, over: [f64; 3], mae: f64, rms: f64, pixels: usize) {
    assert!(
        close(m.over1_pct, over[0]) && close(m.over3_pct, over[1]) && close(m.over5_pct, over[2]),
        "{m:?}, expected >1 >3 >5 = {over:?}"
    );
    // The indices are f32: a shifted index is exact to a few units in the 7th digit.
    let near = |a: f64, b: f64| (a - b).abs() < 1e-5;
    assert!(
        near(m.mae, mae) && near(m.rms, rms),
        "{m:?}, expected MAE {mae} RMS {rms}"
    );
    assert_eq!(m.valid_pixels, pixels, "{m:?}");
}

const ALL: usize = 160 * 640;
const NOT_SKY: usize = (160 - 30) * 640;

#[test]
fn the_ground_truth_itself_scores_zero() {
    let truth = truth();
    let m = eval_metrics(&truth.gt.index, &truth, N).unwrap();
    assert_metrics(&m.reference, [0.0; 3], 0.0, 0.0, NOT_SKY);
    assert_metrics(&m.with_sky, [0.0; 3], 0.0, 0.0, ALL);
}

#[test]
fn a_shift_of_k_indices_scores_k_over_n() {
    let truth = truth();
    for (k, over) in [
        (1.0f32, [100.0, 0.0, 0.0]),
        (2.0, [100.0, 100.0, 0.0]),
        (3.0, [100.0, 100.0, 100.0]),
    ] {
        let e = f64::from(k) / N as f64 * 100.0;
        // Up or down: the error is absolute (sky, at index 0, only shifted up).
        for sign in [1.0f32, -1.0] {
            let pred: Vec<f32> = truth
                .gt
                .index
                .iter()
                .zip(&truth.sky)
                .map(|(&g, &sky)| if sky { g + k } else { g + sign * k })
                .collect();
            let m = eval_metrics(&pred, &truth, N).unwrap();
            assert_metrics(&m.reference, over, e, e, NOT_SKY);
            assert_metrics(&m.with_sky, over, e, e, ALL);
        }
    }
}

#[test]
fn half_the_pixels_wrong_and_unscored_pixels() {
    let truth = truth();
    // Every other column 3 indices off (E = 6), the others exact.
    let pred: Vec<f32> = truth
        .gt
        .index
        .iter()
        .enumerate()
        .map(|(i, &g)| if i % 2 == 0 { g + 3.0 } else { g })
        .collect();
    let m = eval_metrics(&pred, &truth, N).unwrap();
    assert_metrics(&m.reference, [50.0; 3], 3.0, 18f64.sqrt(), NOT_SKY);
    // The columns 3 indices off have no answer: only the exact ones are scored.
    let holes: Vec<f32> = pred
        .iter()
        .enumerate()
        .map(|(i, &p)| if i % 2 == 0 { f32::NAN } else { p })
        .collect();
    let m = eval_metrics(&holes, &truth, N).unwrap();
    assert_metrics(&m.reference, [0.0; 3], 0.0, 0.0, NOT_SKY / 2);
    // The mean over frames weighs each frame the same.
    let exact = eval_metrics(&truth.gt.index, &truth, N).unwrap();
    let off: Vec<f32> = truth.gt.index.iter().map(|&g| g + 3.0).collect();
    let off = eval_metrics(&off, &truth, N).unwrap();
    let mean = ProtocolMetrics::mean(&[exact, off]).unwrap();
    assert!((mean.reference.mae - 3.0).abs() < 1e-5 && close(mean.reference.over5_pct, 50.0));
}

#[test]
fn a_coarser_prediction_is_resampled_to_the_evaluation_grid() {
    let hyps = hyps();
    let grid = eval_grid();
    let truth = eval_truth_on_grid(&ground_truth(|_| 10.0), &hyps, &grid).unwrap();
    // On the evaluation grid with its hypotheses, a prediction is taken as it is.
    let same = index_on_eval_grid(&truth.gt.index, &grid, &hyps, &grid, &hyps).unwrap();
    assert_eq!(same, truth.gt.index);
    // A constant answer of index 20 at a quarter of the resolution: 10 indices off at every
    // pixel after resampling, E = 20.
    let native = EquirectGrid::new(40, 160, 45.0).unwrap();
    let pred = index_on_eval_grid(&vec![20.0; native.len()], &native, &hyps, &grid, &hyps).unwrap();
    assert_eq!(pred.len(), grid.len());
    let m = eval_metrics(&pred, &truth, N).unwrap();
    assert!((m.reference.mae - 20.0).abs() < 1e-3, "{m:?}");
    assert!(close(m.reference.over5_pct, 100.0));
    // Another latitude range cannot be compared.
    let other = EquirectGrid::new(40, 160, 60.0).unwrap();
    let err = index_on_eval_grid(&vec![20.0; other.len()], &other, &hyps, &grid, &hyps)
        .unwrap_err()
        .to_string();
    assert!(err.contains("latitude range"), "{err}");
}
