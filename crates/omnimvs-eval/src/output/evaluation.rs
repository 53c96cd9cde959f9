//! Methods scored side by side at one evaluation sweep: every estimate is brought to the
//! evaluation grid ([`index_on_eval_grid`]) and scored under both protocols; the report is
//! `eval.json` and `eval.md`.

use std::path::{Path, PathBuf};

use omnimvs_data::Dataset;
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::estimate::DepthEstimate;
use omnimvs_data::gt::{EvalTruth, GroundTruth};
use omnimvs_data::image_io::write_png_u8;
use omnimvs_sweep::SweepSpec;
use serde::Serialize;

use super::report::{protocol_tables, write_json, write_text};
use crate::metrics::{Metrics, Protocol, ProtocolMetrics, eval_metrics, index_on_eval_grid};
use omnimvs_data::DataError;

/// The ground truth of some frames on the evaluation sweep.
pub struct Evaluation {
    /// The grid and hypotheses every estimate is scored at.
    pub spec: SweepSpec,
    /// The frames, each with ground truth.
    pub frames: Vec<u32>,
    /// The ground truth of each frame on `spec`, with its sky mask.
    pub truths: Vec<EvalTruth>,
    /// The dataset's folder.
    pub dataset: PathBuf,
}

impl Evaluation {
    /// Reads the ground truth of `frames` on `spec`.
    ///
    /// # Errors
    /// [`DataError`] for a frame without ground truth or an unreadable one.
    pub fn new(ds: &Dataset, frames: &[u32], spec: SweepSpec) -> Result<Self, DataError> {
        let mut truths = Vec::with_capacity(frames.len());
        for &f in frames {
            truths.push(ds.eval_truth(f, &spec)?.ok_or_else(|| {
                DataError::format(&ds.root, format!("frame {f} has no ground truth"))
            })?);
        }
        Ok(Self {
            spec,
            frames: frames.to_vec(),
            truths,
            dataset: ds.root.clone(),
        })
    }

    /// The estimate of the `k`-th frame as indices on the evaluation grid, and its metrics
    /// under both protocols.
    ///
    /// # Errors
    /// [`DataError`] for an estimate that cannot be brought to the evaluation grid.
    pub fn score(
        &self,
        k: usize,
        est: &DepthEstimate,
    ) -> Result<(Vec<f32>, ProtocolMetrics), DataError> {
        let (from, to) = (&est.spec, &self.spec);
        let index = index_on_eval_grid(
            &est.index,
            &from.grid,
            &from.hypotheses,
            &to.grid,
            &to.hypotheses,
        )?;
        let metrics = eval_metrics(&index, &self.truths[k], to.ndepth())?;
        Ok((index, metrics))
    }
}

/// The grid and the number of hypotheses a method answers at.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct NativeGrid {
    pub height: usize,
    pub width: usize,
    pub phi_deg: f64,
    pub ndepth: usize,
}

impl NativeGrid {
    /// The sizes of `spec`.
    pub fn of(spec: &SweepSpec) -> Self {
        Self {
            height: spec.height(),
            width: spec.width(),
            phi_deg: spec.grid.phi_deg,
            ndepth: spec.ndepth(),
        }
    }
}

/// One frame's metrics under both protocols.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FrameScores {
    pub frame: u32,
    /// The `reference` protocol.
    pub metrics: Metrics,
    /// The `with-sky` protocol.
    pub metrics_with_sky: Metrics,
}

/// One method's row of the evaluation.
#[derive(Debug, Serialize)]
pub struct MethodResult {
    pub method: String,
    /// The grid the method answered at, before it was resampled to the evaluation grid.
    pub native: NativeGrid,
    /// Whether the output was resampled (another grid or another N than the evaluation's).
    pub resampled: bool,
    /// Mean over frames, `reference` protocol.
    pub metrics: Metrics,
    /// Mean over frames, `with-sky` protocol.
    pub metrics_with_sky: Metrics,
    pub per_frame: Vec<FrameScores>,
    pub seconds_per_frame: f64,
}

/// A method's scores, frame by frame.
pub struct MethodScores {
    /// The row's name.
    pub name: String,
    native: SweepSpec,
    per_frame: Vec<FrameScores>,
}

impl MethodScores {
    /// No frame yet of the method `name`, which answers on `native`.
    pub fn new(name: impl Into<String>, native: SweepSpec) -> Self {
        Self {
            name: name.into(),
            native,
            per_frame: Vec::new(),
        }
    }

    /// Adds a frame's metrics.
    pub fn push(&mut self, frame: u32, m: ProtocolMetrics) {
        self.per_frame.push(FrameScores {
            frame,
            metrics: m.reference,
            metrics_with_sky: m.with_sky,
        });
    }

    /// The row: means over the frames scored at `eval`.
    ///
    /// # Errors
    /// [`SweepError::Mismatch`](omnimvs_sweep::SweepError::Mismatch) when no frame was scored.
    pub fn finish(
        self,
        eval: &SweepSpec,
        seconds_per_frame: f64,
    ) -> Result<MethodResult, DataError> {
        let all: Vec<ProtocolMetrics> = self
            .per_frame
            .iter()
            .map(|p| ProtocolMetrics {
                reference: p.metrics,
                with_sky: p.metrics_with_sky,
            })
            .collect();
        let mean = ProtocolMetrics::mean(&all)
            .ok_or_else(|| DataError::mismatch(format!("frames of {}", self.name), "1", "0"))?;
        Ok(MethodResult {
            method: self.name,
            native: NativeGrid::of(&self.native),
            resampled: self.native != *eval,
            metrics: mean.reference,
            metrics_with_sky: mean.with_sky,
            per_frame: self.per_frame,
            seconds_per_frame,
        })
    }
}

/// What each metrics field of the report holds.
#[derive(Serialize)]
struct ProtocolNames {
    metrics: String,
    metrics_with_sky: String,
}

/// The evaluation's report (`eval.json`).
#[derive(Serialize)]
pub struct EvalReport {
    dataset: PathBuf,
    frames: Vec<u32>,
    /// The evaluation grid every output is scored at.
    height: usize,
    width: usize,
    phi_deg: f64,
    ndepth: usize,
    /// The protocol of the `metrics` fields (the paper's).
    protocol: Protocol,
    protocols: ProtocolNames,
    /// One row per method.
    pub methods: Vec<MethodResult>,
}

impl EvalReport {
    /// The report of `methods` scored by `eval`.
    pub fn new(eval: &Evaluation, methods: Vec<MethodResult>) -> Self {
        let names = |p: Protocol| format!("{p}: {}", p.description());
        Self {
            dataset: eval.dataset.clone(),
            frames: eval.frames.clone(),
            height: eval.spec.height(),
            width: eval.spec.width(),
            phi_deg: eval.spec.grid.phi_deg,
            ndepth: eval.spec.ndepth(),
            protocol: Protocol::Reference,
            protocols: ProtocolNames {
                metrics: names(Protocol::Reference),
                metrics_with_sky: names(Protocol::WithSky),
            },
            methods,
        }
    }

    /// Both protocols' tables with a line on the dataset, frames and evaluation grid (`eval.md`).
    pub fn table(&self) -> String {
        let rows: Vec<(String, ProtocolMetrics)> = self
            .methods
            .iter()
            .map(|m| {
                let n = &m.native;
                (
                    format!(
                        "{}, native {}x{}, N = {}",
                        m.method, n.height, n.width, n.ndepth
                    ),
                    ProtocolMetrics {
                        reference: m.metrics,
                        with_sky: m.metrics_with_sky,
                    },
                )
            })
            .collect();
        let (first, last) = (
            self.frames.first().copied().unwrap_or_default(),
            self.frames.last().copied().unwrap_or_default(),
        );
        format!(
            "{} frames {first}..{last} ({} frames), evaluation grid {}x{} (+-{} deg), N = {}; \
             each method at its own grid, resampled to this one\n\n{}",
            self.dataset.display(),
            self.frames.len(),
            self.height,
            self.width,
            self.phi_deg,
            self.ndepth,
            protocol_tables(&rows)
        )
    }

    /// Writes `out/eval.json` and `out/eval.md`.
    ///
    /// # Errors
    /// [`DataError`] naming a file that cannot be written.
    pub fn write(&self, out: &Path) -> Result<(), DataError> {
        write_json(&out.join("eval.json"), self, true)?;
        write_text(&out.join("eval.md"), &self.table())
    }
}

/// Writes hypothesis indices on the ground truth's grid as a turbo PNG over `[0, N - 1]`,
/// black where the ground truth is invalid when `mask`.
///
/// # Errors
/// [`DataError`] naming a file that cannot be written.
pub fn write_index_png(
    path: &Path,
    index: &[f32],
    gt: &GroundTruth,
    ndepth: usize,
    mask: bool,
) -> Result<(), DataError> {
    let valid = mask.then_some(gt.valid.as_slice());
    let rgb = colorize(index, 0.0, (ndepth - 1) as f64, Colormap::Turbo, valid);
    write_png_u8(path, gt.width, gt.height, 3, &rgb)
}
