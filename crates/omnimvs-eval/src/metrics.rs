//! The paper's error metrics (`FORMATS.md`, "Evaluation metrics").
//!
//! Per pixel `E = |n_hat - n*| / N * 100`; per frame the percentages of valid
//! pixels with `E > 1`, `> 3`, `> 5`, the mean (MAE) and the root mean square
//! (RMS) of `E`; a dataset's figures are the mean over its frames.
//!
//! Two protocols ([`Protocol`]) decide which pixels count: `reference`, the
//! reference implementation's `evalError` and the paper's tables (sky is not
//! scored), the default of every command; and `with-sky`, which scores sky as
//! index 0, as training sees it (a robot must not see obstacles in the sky).
//! A method's output on its own grid is brought to the evaluation grid by
//! [`index_on_eval_grid`].

use std::fmt;

use omnimvs_data::gt::{EvalTruth, GroundTruth};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, resample_map};
use serde::{Deserialize, Serialize};

use omnimvs_data::DataError;

/// Which ground-truth pixels a score counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Protocol {
    /// The reference implementation's `loadGTInvdepthIndex` + `evalError`, the paper's
    /// tables: ground truth of inverse depth 0 (sky) has index `(0 - d_0) / step`, just
    /// below 0, and only `0 <= n* <= N` is scored, so sky is not; holes of the invalid rule
    /// are not scored either.
    #[default]
    Reference,
    /// Every valid pixel of the training ground truth, sky scored as index 0 (holes of the
    /// invalid rule are still not scored).
    WithSky,
}

impl Protocol {
    /// Both protocols, the default first.
    pub const ALL: [Self; 2] = [Self::Reference, Self::WithSky];

    /// The protocol's name in reports and JSON: `reference` or `with-sky`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Reference => "reference",
            Self::WithSky => "with-sky",
        }
    }

    /// One line on which pixels are scored.
    pub fn description(self) -> &'static str {
        match self {
            Self::Reference => {
                "the reference's evalError, as in the paper's tables; sky, whose index is just below 0 there, is not scored"
            }
            Self::WithSky => "sky scored as index 0, as in training",
        }
    }

    /// Whether pixel `i` of `truth` is scored: valid in the ground truth, and not sky for the
    /// `reference` protocol.
    pub fn scores(self, truth: &EvalTruth, i: usize) -> bool {
        truth.gt.valid[i]
            && match self {
                Self::Reference => !truth.sky[i],
                Self::WithSky => true,
            }
    }
}

impl fmt::Display for Protocol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

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
    /// Percentage of the pixels the protocol scores that have an answer (a finite
    /// prediction); the other figures are over those. 100 unless a method leaves pixels
    /// without an answer (`sgm --min-confidence`).
    #[serde(default = "full_coverage")]
    pub coverage_pct: f64,
}

fn full_coverage() -> f64 {
    100.0
}

/// The metrics of one frame: `pred_index` holds `n_hat` for every pixel of
/// the ground truth's grid. Pixels invalid in the ground truth or with a
/// non-finite prediction are skipped, as in the reference. Sky pixels, valid at
/// index 0 in a [`GroundTruth`], are scored: this is the `with-sky` protocol;
/// [`protocol_metrics`] scores either protocol.
///
/// # Errors
/// [`SweepError::Mismatch`](omnimvs_sweep::SweepError::Mismatch) when the sizes differ or no pixel is valid.
pub fn frame_metrics(
    pred_index: &[f32],
    gt: &GroundTruth,
    ndepth: usize,
) -> Result<Metrics, DataError> {
    metrics_where(pred_index, gt, ndepth, "valid ground-truth pixels", |i| {
        gt.valid[i]
    })
}

/// The metrics of one frame under `protocol`: as [`frame_metrics`], over the pixels that
/// `truth` scores under `protocol` ([`Protocol::scores`]).
///
/// # Errors
/// [`SweepError::Mismatch`](omnimvs_sweep::SweepError::Mismatch) when the sizes differ or no pixel is scored.
pub fn protocol_metrics(
    pred_index: &[f32],
    truth: &EvalTruth,
    ndepth: usize,
    protocol: Protocol,
) -> Result<Metrics, DataError> {
    if truth.sky.len() != truth.gt.valid.len() {
        return Err(DataError::mismatch(
            "sky mask size",
            truth.gt.valid.len(),
            truth.sky.len(),
        ));
    }
    let what = format!("ground-truth pixels scored by the {protocol} protocol");
    metrics_where(pred_index, &truth.gt, ndepth, &what, |i| {
        protocol.scores(truth, i)
    })
}

/// The metrics of one frame under both protocols.
///
/// # Errors
/// As [`protocol_metrics`].
pub fn eval_metrics(
    pred_index: &[f32],
    truth: &EvalTruth,
    ndepth: usize,
) -> Result<ProtocolMetrics, DataError> {
    Ok(ProtocolMetrics {
        reference: protocol_metrics(pred_index, truth, ndepth, Protocol::Reference)?,
        with_sky: protocol_metrics(pred_index, truth, ndepth, Protocol::WithSky)?,
    })
}

fn pct_of(part: usize, whole: usize) -> f64 {
    part as f64 / whole.max(1) as f64 * 100.0
}

/// The metrics over the pixels `i` with `scored(i)` and a finite prediction.
fn metrics_where(
    pred_index: &[f32],
    gt: &GroundTruth,
    ndepth: usize,
    what: &str,
    scored: impl Fn(usize) -> bool,
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
    let mut asked = 0usize;
    for (i, (&p, &g)) in pred_index.iter().zip(&gt.index).enumerate() {
        if !scored(i) {
            continue;
        }
        asked += 1;
        if !p.is_finite() {
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
        return Err(DataError::mismatch(what, "at least one", 0));
    }
    let pct = |k: usize| k as f64 / n as f64 * 100.0;
    Ok(Metrics {
        over1_pct: pct(o1),
        over3_pct: pct(o3),
        over5_pct: pct(o5),
        mae: sum / n as f64,
        rms: (sum_sq / n as f64).sqrt(),
        valid_pixels: n,
        coverage_pct: pct_of(n, asked),
    })
}

/// One frame's (or a mean's) metrics under both protocols.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProtocolMetrics {
    /// The `reference` protocol: the paper's figures, the default.
    pub reference: Metrics,
    /// The `with-sky` protocol.
    pub with_sky: Metrics,
}

impl ProtocolMetrics {
    /// The metrics of `protocol`.
    pub fn get(&self, protocol: Protocol) -> &Metrics {
        match protocol {
            Protocol::Reference => &self.reference,
            Protocol::WithSky => &self.with_sky,
        }
    }

    /// The mean over frames of each protocol ([`mean_metrics`]); `None` for no frame.
    pub fn mean(frames: &[Self]) -> Option<Self> {
        let of = |p: Protocol| frames.iter().map(|m| *m.get(p)).collect::<Vec<_>>();
        Some(Self {
            reference: mean_metrics(&of(Protocol::Reference))?,
            with_sky: mean_metrics(&of(Protocol::WithSky))?,
        })
    }
}

/// A method's hypothesis-index map on its own grid (`native`, indices of `native_hyps`) as
/// indices of `eval_hyps` on the evaluation grid `eval`: each index is turned into inverse
/// depth with the method's own hypotheses, the inverse-depth map is resampled on the sphere
/// ([`resample_map`]: bilinear, longitude wrapping around) and turned back into an index of
/// the evaluation's `N`. A map already on the evaluation grid with the same hypotheses is
/// returned as it is. Non-finite values stay non-finite (and are not scored).
///
/// # Errors
/// [`SweepError::Mismatch`](omnimvs_sweep::SweepError::Mismatch) when the map is not `native`'s size, or when the two grids cover
/// different latitudes or the hypotheses different depth ranges (nothing to resample then).
pub fn index_on_eval_grid(
    index: &[f32],
    native: &EquirectGrid,
    native_hyps: &InvDepthHypotheses,
    eval: &EquirectGrid,
    eval_hyps: &InvDepthHypotheses,
) -> Result<Vec<f32>, DataError> {
    if index.len() != native.len() {
        return Err(DataError::mismatch(
            "prediction size",
            format!("{} x {} = {}", native.height, native.width, native.len()),
            index.len(),
        ));
    }
    if (native.phi_deg - eval.phi_deg).abs() > 1e-9 {
        return Err(DataError::mismatch(
            format!(
                "latitude range of a {}x{} prediction",
                native.height, native.width
            ),
            format!(
                "±{} degrees (the {}x{} evaluation grid)",
                eval.phi_deg, eval.height, eval.width
            ),
            format!("±{} degrees", native.phi_deg),
        ));
    }
    if (native_hyps.min_depth_m - eval_hyps.min_depth_m).abs() > 1e-12 {
        return Err(DataError::mismatch(
            "minimum depth of the prediction's hypotheses",
            format!("{} m (the evaluation's)", eval_hyps.min_depth_m),
            format!("{} m", native_hyps.min_depth_m),
        ));
    }
    if native == eval && native_hyps == eval_hyps {
        return Ok(index.to_vec());
    }
    let inv_depth: Vec<f32> = index
        .iter()
        .map(|&n| native_hyps.inv_depth(f64::from(n)) as f32)
        .collect();
    let resampled = if native == eval {
        inv_depth
    } else {
        resample_map(&inv_depth, native, eval)
    };
    Ok(resampled
        .iter()
        .map(|&d| eval_hyps.index(f64::from(d)) as f32)
        .collect())
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
        coverage_pct: mean(|m| m.coverage_pct),
    })
}

impl Metrics {
    /// The Markdown header matching [`Self::markdown_row`].
    pub const MARKDOWN_HEADER: &'static str =
        "| method | >1 (%) | >3 (%) | >5 (%) | MAE | RMS |\n|---|---:|---:|---:|---:|---:|";

    /// A Markdown table row; a method that leaves pixels without an answer shows its
    /// coverage beside its name.
    pub fn markdown_row(&self, method: &str) -> String {
        let method = if self.coverage_pct < 99.995 {
            format!("{method} (coverage {:.1} %)", self.coverage_pct)
        } else {
            method.to_string()
        };
        format!(
            "| {method} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            self.over1_pct, self.over3_pct, self.over5_pct, self.mae, self.rms
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};

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

    /// `N = 100` spheres with a step of exactly 0.01 (1/m) up to `d_0`: the index of an
    /// inverse depth `d` is `100 d`, and `E` equals the index error.
    fn hundred() -> InvDepthHypotheses {
        InvDepthHypotheses::new(100, 1.0 / 0.99).unwrap()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-4
    }

    /// An inverse-depth map of one row (1/m).
    fn one_row(data: Vec<f32>) -> omnimvs_data::gt::InvDepthMap {
        omnimvs_data::gt::InvDepthMap {
            width: data.len(),
            height: 1,
            data,
        }
    }

    #[test]
    fn both_protocols_on_a_hand_made_frame() {
        use omnimvs_data::gt::eval_truth_index;
        // One row: two sky pixels, four at 10, 5, 3.33 and 2.5 m. A single row has no hole
        // (the 5x5 closing erodes everything next to the border).
        let truth = eval_truth_index(&one_row(vec![0.0, 0.0, 0.1, 0.2, 0.3, 0.4]), &hundred());
        assert_eq!(truth.sky, [true, true, false, false, false, false]);
        assert!(
            truth.gt.valid.iter().all(|&v| v),
            "training's truth keeps sky"
        );
        assert_eq!(truth.gt.index[0], 0.0);
        // E per pixel: sky 0 and 4; then 0, 2, 6; the last prediction is NaN (skipped).
        let pred = [0.0, 4.0, 10.0, 22.0, 36.0, f32::NAN];
        let m = eval_metrics(&pred, &truth, 100).unwrap();
        // Reference: E = 0, 2, 6 over 3 pixels.
        let r = m.reference;
        assert_eq!(r.valid_pixels, 3);
        assert!(close(r.over1_pct, 200.0 / 3.0), "{r:?}");
        assert!(close(r.over3_pct, 100.0 / 3.0) && close(r.over5_pct, 100.0 / 3.0));
        assert!(close(r.mae, 8.0 / 3.0) && close(r.rms, (40.0f64 / 3.0).sqrt()));
        // With sky: E = 0, 4, 0, 2, 6 over 5 pixels.
        let w = m.with_sky;
        assert_eq!(w.valid_pixels, 5);
        assert!(
            close(w.over1_pct, 60.0) && close(w.over3_pct, 40.0),
            "{w:?}"
        );
        assert!(close(w.over5_pct, 20.0) && close(w.mae, 2.4));
        assert!(close(w.rms, (56.0f64 / 5.0).sqrt()));
        // `with-sky` is what `frame_metrics` has always scored.
        assert_eq!(frame_metrics(&pred, &truth.gt, 100).unwrap(), w);
        assert_eq!(*m.get(Protocol::Reference), r);
        // A frame of sky only has nothing to score by the reference's rule.
        let sky = eval_truth_index(&one_row(vec![0.0; 3]), &hundred());
        let err = protocol_metrics(&[0.0; 3], &sky, 100, Protocol::Reference).unwrap_err();
        assert!(err.to_string().contains("reference protocol"), "{err}");
        assert_eq!(
            protocol_metrics(&[0.0; 3], &sky, 100, Protocol::WithSky)
                .unwrap()
                .valid_pixels,
            3
        );
        let mean = ProtocolMetrics::mean(&[m, m]).unwrap();
        assert!(close(mean.reference.mae, r.mae) && mean.with_sky.valid_pixels == 10);
        assert_eq!(
            serde_json::to_string(&Protocol::WithSky).unwrap(),
            "\"with-sky\""
        );
        assert_eq!(Protocol::default(), Protocol::Reference);
    }

    #[test]
    fn a_constant_map_stays_constant_on_the_evaluation_grid() {
        let hyps64 = InvDepthHypotheses::new(64, 0.5).unwrap();
        let hyps192 = InvDepthHypotheses::new(192, 0.5).unwrap();
        let coarse = EquirectGrid::new(32, 128, 45.0).unwrap();
        let eval = EquirectGrid::new(160, 640, 45.0).unwrap();
        let out = index_on_eval_grid(&vec![21.0; coarse.len()], &coarse, &hyps64, &eval, &hyps192)
            .unwrap();
        assert_eq!(out.len(), eval.len());
        // The same inverse depth in the finer N: index 21 of 63 steps is 63.667 of 191.
        let want = 21.0 * 191.0 / 63.0;
        assert!(out.iter().all(|&n| (f64::from(n) - want).abs() < 1e-4));
        // The evaluation grid with its own hypotheses: returned as it is.
        let same: Vec<f32> = (0..eval.len()).map(|i| (i % 191) as f32).collect();
        assert_eq!(
            index_on_eval_grid(&same, &eval, &hyps192, &eval, &hyps192).unwrap(),
            same
        );
        // Another latitude range or size is refused.
        let wide = EquirectGrid::new(32, 128, 90.0).unwrap();
        let err = index_on_eval_grid(&vec![0.0; wide.len()], &wide, &hyps64, &eval, &hyps192)
            .unwrap_err();
        assert!(err.to_string().contains("latitude"), "{err}");
        assert!(index_on_eval_grid(&[0.0; 5], &coarse, &hyps64, &eval, &hyps192).is_err());
    }

    #[test]
    fn a_coarse_map_is_upsampled_on_the_sphere_before_it_is_scored() {
        use omnimvs_data::gt::{InvDepthMap, eval_truth_on_grid};
        let hyps64 = InvDepthHypotheses::new(64, 0.5).unwrap();
        let hyps192 = InvDepthHypotheses::new(192, 0.5).unwrap();
        let coarse = EquirectGrid::new(32, 128, 45.0).unwrap();
        let eval = EquirectGrid::new(160, 640, 45.0).unwrap();
        // A smooth scene on the 320x640 (±90 degrees) ground-truth grid: inverse depth
        // varies with longitude, no sky, no hole.
        let source = EquirectGrid::new(320, 640, 90.0).unwrap();
        let scene = |g: &EquirectGrid, _row: usize, col: usize| {
            (0.8 + 0.4 * g.theta_rad(col as f64).sin()) as f32
        };
        let map = InvDepthMap {
            width: 640,
            height: 320,
            data: (0..source.len())
                .map(|i| scene(&source, i / 640, i % 640))
                .collect(),
        };
        let truth = eval_truth_on_grid(&map, &hyps192, &eval).unwrap();
        assert!(truth.sky.iter().all(|&s| !s) && truth.gt.valid.iter().all(|&v| v));
        // The scene's own values on the coarse grid, as a perfect coarse method would answer.
        let coarse_index: Vec<f32> = (0..coarse.len())
            .map(|i| {
                let d = scene(&coarse, i / coarse.width, i % coarse.width);
                hyps64.index(f64::from(d)) as f32
            })
            .collect();
        let index = index_on_eval_grid(&coarse_index, &coarse, &hyps64, &eval, &hyps192).unwrap();
        // The upsampled map lands on the right rays: on the columns the two grids share
        // (every 5th), it equals the ground truth (a half-pixel shift would be 0.3 index
        // units off), and in between it is off by the interpolation's error only.
        for row in [0usize, 77, 159] {
            for col in (0..640).step_by(5) {
                let i = row * 640 + col;
                assert!((index[i] - truth.gt.index[i]).abs() < 0.02, "{row},{col}");
            }
        }
        let m = protocol_metrics(&index, &truth, 192, Protocol::Reference).unwrap();
        assert_eq!(m.valid_pixels, eval.len());
        assert!(m.mae < 0.05 && m.over1_pct == 0.0, "{m:?}");
        // Scoring the coarse map without resampling it would be refused (another size).
        assert!(protocol_metrics(&coarse_index, &truth, 192, Protocol::Reference).is_err());
    }
}
