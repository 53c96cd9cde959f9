//! The paper's error metrics (`FORMATS.md`, "Evaluation metrics").
//!
//! Per pixel `E = |n_hat - n*| / N * 100`; per frame the percentages of valid
//! pixels with `E > 1`, `> 3`, `> 5`, the mean (MAE) and the root mean square
//! (RMS) of `E`; a dataset's figures are the mean over its frames.

use serde::{Deserialize, Serialize};

use crate::DataError;
use crate::gt::GroundTruth;

/// One row of the paper's tables.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Percentage of valid pixels with `E > 1`.
    pub over1_pct: f64,
    /// Percentage with `E > 3`.
    pub over3_pct: f64,
    /// Percentage with `E > 5`.
    pub over5_pct: f64,
    /// Mean absolute error, in percent of `N`.
    pub mae: f64,
    /// Root mean square error, in percent of `N`.
    pub rms: f64,
    /// Number of pixels evaluated (summed over frames for a mean).
    pub valid_pixels: usize,
}

/// The metrics of one frame: `pred_index` holds `n_hat` for every pixel of
/// the ground truth's grid. Pixels invalid in the ground truth or with a
/// non-finite prediction are skipped, as in the reference.
///
/// # Errors
/// [`DataError::Mismatch`] when the sizes differ or no pixel is valid.
pub fn frame_metrics(
    pred_index: &[f32],
    gt: &GroundTruth,
    ndepth: usize,
) -> Result<Metrics, DataError> {
    if pred_index.len() != gt.index.len() {
        return Err(DataError::mismatch(
            "prediction size",
            format!("{} x {} = {}", gt.height, gt.width, gt.index.len()),
            pred_index.len(),
        ));
    }
    let (mut n, mut o1, mut o3, mut o5, mut sum, mut sum_sq) =
        (0usize, 0usize, 0usize, 0usize, 0f64, 0f64);
    for ((&p, &g), &v) in pred_index.iter().zip(&gt.index).zip(&gt.valid) {
        if !v || !p.is_finite() {
            continue;
        }
        let e = f64::from((p - g).abs()) / ndepth as f64 * 100.0;
        n += 1;
        o1 += usize::from(e > 1.0);
        o3 += usize::from(e > 3.0);
        o5 += usize::from(e > 5.0);
        sum += e;
        sum_sq += e * e;
    }
    if n == 0 {
        return Err(DataError::mismatch(
            "valid ground-truth pixels",
            "at least one",
            0,
        ));
    }
    let pct = |k: usize| k as f64 / n as f64 * 100.0;
    Ok(Metrics {
        over1_pct: pct(o1),
        over3_pct: pct(o3),
        over5_pct: pct(o5),
        mae: sum / n as f64,
        rms: (sum_sq / n as f64).sqrt(),
        valid_pixels: n,
    })
}

/// The mean over frames (each frame weighs the same, as in the paper);
/// `None` for no frame.
pub fn mean_metrics(frames: &[Metrics]) -> Option<Metrics> {
    if frames.is_empty() {
        return None;
    }
    let k = frames.len() as f64;
    let mean = |f: fn(&Metrics) -> f64| frames.iter().map(f).sum::<f64>() / k;
    Some(Metrics {
        over1_pct: mean(|m| m.over1_pct),
        over3_pct: mean(|m| m.over3_pct),
        over5_pct: mean(|m| m.over5_pct),
        mae: mean(|m| m.mae),
        rms: mean(|m| m.rms),
        valid_pixels: frames.iter().map(|m| m.valid_pixels).sum(),
    })
}

impl Metrics {
    /// The Markdown header matching [`Self::markdown_row`].
    pub const MARKDOWN_HEADER: &'static str =
        "| method | >1 (%) | >3 (%) | >5 (%) | MAE | RMS |\n|---|---:|---:|---:|---:|---:|";

    /// A Markdown table row.
    pub fn markdown_row(&self, method: &str) -> String {
        format!(
            "| {method} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            self.over1_pct, self.over3_pct, self.over5_pct, self.mae, self.rms
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gt(index: Vec<f32>, valid: Vec<bool>) -> GroundTruth {
        GroundTruth {
            width: index.len(),
            height: 1,
            index,
            valid,
        }
    }

    #[test]
    fn hand_computed_frame() {
        // N = 100, so E equals the index error.
        let g = gt(
            vec![10.0, 10.0, 10.0, 10.0, 10.0],
            vec![true, true, true, true, false],
        );
        let pred = [10.0, 12.0, 14.0, 20.0, 99.0];
        let m = frame_metrics(&pred, &g, 100).unwrap();
        assert_eq!(m.valid_pixels, 4);
        assert!((m.over1_pct - 75.0).abs() < 1e-9);
        assert!((m.over3_pct - 50.0).abs() < 1e-9);
        assert!((m.over5_pct - 25.0).abs() < 1e-9);
        assert!((m.mae - 4.0).abs() < 1e-9);
        assert!((m.rms - (120f64 / 4.0).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn nan_predictions_are_skipped_and_mean_is_per_frame() {
        let g = gt(vec![0.0, 0.0], vec![true, true]);
        let a = frame_metrics(&[f32::NAN, 2.0], &g, 100).unwrap();
        assert_eq!(a.valid_pixels, 1);
        let b = frame_metrics(&[0.0, 0.0], &g, 100).unwrap();
        let m = mean_metrics(&[a, b]).unwrap();
        assert!((m.mae - 1.0).abs() < 1e-9);
        assert!(frame_metrics(&[0.0], &g, 100).is_err());
        assert!(mean_metrics(&[]).is_none());
    }
}
