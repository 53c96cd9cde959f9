//! A method's outputs over a dataset's frames, frame by frame, then the reports: the layout
//! of a method with a confidence (`omnimvs sgm`) and of a network (`omnimvs infer`).

use std::path::{Path, PathBuf};

use omnimvs_data::Dataset;
use omnimvs_data::estimate::{DepthEstimate, StageTimes};
use omnimvs_data::gt::EvalTruth;
use omnimvs_sweep::SweepSpec;
use serde::Serialize;

use super::files::{FrameScene, write_depth_pictures, write_maps, write_percentile_png};
use super::report::{
    ConfidenceFrame, ConfidenceSummary, frames_table, metrics_json, write_json, write_text,
};
use crate::metrics::{Protocol, ProtocolMetrics, eval_metrics};
use omnimvs_data::DataError;

fn create_dir(dir: &Path) -> Result<(), DataError> {
    std::fs::create_dir_all(dir).map_err(|e| DataError::io(dir, e))
}

/// The metrics of an estimate against `truth` (on its grid), when there is a truth.
fn metrics_of(
    est: &DepthEstimate,
    truth: Option<&EvalTruth>,
) -> Result<Option<ProtocolMetrics>, DataError> {
    truth
        .map(|t| eval_metrics(&est.index, t, est.spec.ndepth()))
        .transpose()
}

/// The outputs of a method with a confidence map in a folder: per frame the maps
/// ([`write_maps`]) and `_invdepth.png`; at the end `metrics.md` (when frames have ground
/// truth) and the summary JSON.
pub struct ConfidenceRun {
    dir: PathBuf,
    spec: SweepSpec,
    frames: Vec<ConfidenceFrame>,
}

impl ConfidenceRun {
    /// A run writing into `dir` (created) on `spec`.
    ///
    /// # Errors
    /// [`DataError`] when the folder cannot be created.
    pub fn new(dir: &Path, spec: SweepSpec) -> Result<Self, DataError> {
        create_dir(dir)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            spec,
            frames: Vec::new(),
        })
    }

    /// Writes a frame's files and scores it against `truth` (on the estimate's grid).
    ///
    /// # Errors
    /// [`DataError`] for a file that cannot be written or a truth of another size.
    pub fn add(
        &mut self,
        frame: u32,
        est: &DepthEstimate,
        timings: StageTimes,
        truth: Option<&EvalTruth>,
    ) -> Result<&ConfidenceFrame, DataError> {
        write_maps(&self.dir, frame, est)?;
        let color_range = write_percentile_png(&self.dir, frame, est)?;
        let metrics = metrics_of(est, truth)?;
        let conf = est.confidence.as_deref().unwrap_or_default();
        self.frames.push(ConfidenceFrame {
            frame,
            timings,
            color_range,
            mean_confidence: conf.iter().sum::<f32>() / conf.len() as f32,
            metrics: metrics.map(|m| m.reference),
            metrics_with_sky: metrics.map(|m| m.with_sky),
        });
        Ok(&self.frames[self.frames.len() - 1])
    }

    /// Number of frames written.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether no frame was written.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Writes `metrics.md` (the per-frame and mean tables, returned) when frames had ground
    /// truth, and `json_name` summarising the run of `method` with `params` on `ds`.
    ///
    /// # Errors
    /// [`DataError`] naming a file that cannot be written.
    pub fn finish<P: Serialize>(
        self,
        ds: &Dataset,
        method: &str,
        params: P,
        json_name: &str,
    ) -> Result<Option<String>, DataError> {
        let per_frame: Vec<(u32, ProtocolMetrics)> = self
            .frames
            .iter()
            .filter_map(|r| Some((r.frame, r.protocol_metrics()?)))
            .collect();
        let all: Vec<ProtocolMetrics> = per_frame.iter().map(|(_, m)| *m).collect();
        let mean = ProtocolMetrics::mean(&all);
        let (h, w, n) = (self.spec.height(), self.spec.width(), self.spec.ndepth());
        let title = format!(
            "{} ({} frames with ground truth), {h}x{w}, N = {n}",
            ds.root.display(),
            per_frame.len()
        );
        let table = frames_table(&title, &per_frame, &format!("{method} (mean)"));
        if let Some(table) = &table {
            write_text(&self.dir.join("metrics.md"), table)?;
        }
        let summary = ConfidenceSummary {
            method,
            dataset: ds.root.display().to_string(),
            height: h,
            width: w,
            phi_deg: self.spec.grid.phi_deg,
            ndepth: n,
            min_depth_m: ds.config.min_depth_m,
            rig_frame: &ds.frame,
            params,
            protocol: Protocol::Reference,
            frames: &self.frames,
            mean_metrics: mean.map(|m| m.reference),
            mean_metrics_with_sky: mean.map(|m| m.with_sky),
        };
        write_json(&self.dir.join(json_name), &summary, false)?;
        Ok(table)
    }
}

/// The outputs of a network in a folder: `infer.json` (the settings), per frame the maps
/// ([`write_maps`]) and pictures ([`write_depth_pictures`]); at the end `metrics.json` when
/// frames have ground truth.
pub struct DepthRun {
    dir: PathBuf,
    ply: bool,
    metrics: Vec<(u32, ProtocolMetrics)>,
}

impl DepthRun {
    /// A run writing into `dir` (created), its `settings` in `settings_name`, point clouds
    /// when `ply`.
    ///
    /// # Errors
    /// [`DataError`] when the folder or the settings cannot be written.
    pub fn new(
        dir: &Path,
        settings_name: &str,
        settings: &impl Serialize,
        ply: bool,
    ) -> Result<Self, DataError> {
        create_dir(dir)?;
        write_json(&dir.join(settings_name), settings, true)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            ply,
            metrics: Vec::new(),
        })
    }

    /// Writes a frame's files; returns its metrics against `truth` (on the estimate's grid).
    ///
    /// # Errors
    /// [`DataError`] for a file that cannot be written or images that do not fit the rig.
    pub fn add(
        &mut self,
        frame: u32,
        est: &DepthEstimate,
        scene: FrameScene<'_>,
        truth: Option<&EvalTruth>,
    ) -> Result<Option<ProtocolMetrics>, DataError> {
        write_maps(&self.dir, frame, est)?;
        let metrics = metrics_of(est, truth)?;
        write_depth_pictures(&self.dir, frame, est, scene, truth.map(|t| &t.gt), self.ply)?;
        if let Some(m) = metrics {
            self.metrics.push((frame, m));
        }
        Ok(metrics)
    }

    /// Writes `metrics.json` when frames had ground truth; returns the mean metrics.
    ///
    /// # Errors
    /// [`DataError`] naming a file that cannot be written.
    pub fn finish(self) -> Result<Option<ProtocolMetrics>, DataError> {
        if self.metrics.is_empty() {
            return Ok(None);
        }
        let json = metrics_json(&self.metrics);
        write_json(&self.dir.join("metrics.json"), &json, true)?;
        let all: Vec<ProtocolMetrics> = self.metrics.iter().map(|(_, m)| *m).collect();
        Ok(ProtocolMetrics::mean(&all))
    }
}
