//! Reports of a run over frames: Markdown tables of the paper's metrics under both protocols,
//! the classical method's `sgm.json`, a network's `metrics.json`, written atomically.

use std::path::Path;

use omnimvs_core::fs::write_atomic;
use omnimvs_data::estimate::StageTimes;
use serde::Serialize;

use crate::metrics::{Metrics, Protocol, ProtocolMetrics};
use omnimvs_data::DataError;

/// Writes `text` to `path` atomically.
///
/// # Errors
/// [`DataError`] naming the file.
pub fn write_text(path: &Path, text: &str) -> Result<(), DataError> {
    write_atomic(path, text.as_bytes()).map_err(|e| DataError::io(path, e))
}

/// Writes `value` as pretty JSON to `path` atomically, with a final newline when `newline`.
///
/// # Errors
/// [`DataError`] naming the file.
pub fn write_json(path: &Path, value: &impl Serialize, newline: bool) -> Result<(), DataError> {
    let mut text = serde_json::to_string_pretty(value)
        .map_err(|e| DataError::format(path, format!("cannot serialise: {e}")))?;
    if newline {
        text.push('\n');
    }
    write_text(path, &text)
}

/// The heading of one protocol's table.
pub fn protocol_heading(protocol: Protocol) -> String {
    format!(
        "Protocol `{}` ({})",
        protocol.name(),
        protocol.description()
    )
}

/// One Markdown table per protocol (the `reference` one first), each row labelled.
pub fn protocol_tables(rows: &[(String, ProtocolMetrics)]) -> String {
    let mut text = String::new();
    for (k, protocol) in Protocol::ALL.into_iter().enumerate() {
        if k > 0 {
            text.push('\n');
        }
        text.push_str(&protocol_heading(protocol));
        text.push_str(":\n\n");
        text.push_str(Metrics::MARKDOWN_HEADER);
        text.push('\n');
        for (label, m) in rows {
            text.push_str(&m.get(protocol).markdown_row(label));
            text.push('\n');
        }
    }
    text
}

/// One frame of the classical method's report.
#[derive(Debug, Clone, Serialize)]
pub struct ConfidenceFrame {
    pub frame: u32,
    /// Each stage's wall time.
    pub timings: StageTimes,
    /// Inverse depths (1/m) at the ends of the colour map.
    pub color_range: [f32; 2],
    pub mean_confidence: f32,
    /// The `reference` protocol.
    pub metrics: Option<Metrics>,
    /// The `with-sky` protocol.
    pub metrics_with_sky: Option<Metrics>,
}

impl ConfidenceFrame {
    /// Both protocols' metrics, when the frame has ground truth.
    pub fn protocol_metrics(&self) -> Option<ProtocolMetrics> {
        Some(ProtocolMetrics {
            reference: self.metrics?,
            with_sky: self.metrics_with_sky?,
        })
    }
}

/// The report of a method with a confidence over a dataset's frames (`sgm.json`): the sweep,
/// the method's parameters `P`, every frame and the mean metrics.
#[derive(Debug, Serialize)]
pub struct ConfidenceSummary<'a, P: Serialize> {
    pub method: &'a str,
    pub dataset: String,
    pub height: usize,
    pub width: usize,
    pub phi_deg: f64,
    pub ndepth: usize,
    pub min_depth_m: f64,
    /// The frame the rig, and so the outputs, are expressed in.
    pub rig_frame: &'a omnimvs_data::RigFrame,
    pub params: P,
    /// The protocol of the `metrics` fields; `metrics_with_sky` scores sky too.
    pub protocol: Protocol,
    pub frames: &'a [ConfidenceFrame],
    pub mean_metrics: Option<Metrics>,
    pub mean_metrics_with_sky: Option<Metrics>,
}

/// The per-frame and mean metrics of the frames with ground truth as one table per protocol,
/// headed by `title`; the last row is `mean_label`. `None` when no frame has ground truth.
pub fn frames_table(
    title: &str,
    per_frame: &[(u32, ProtocolMetrics)],
    mean_label: &str,
) -> Option<String> {
    let all: Vec<ProtocolMetrics> = per_frame.iter().map(|(_, m)| *m).collect();
    let mean = ProtocolMetrics::mean(&all)?;
    let mut rows: Vec<(String, ProtocolMetrics)> = per_frame
        .iter()
        .map(|(f, fm)| (format!("frame {f}"), *fm))
        .collect();
    rows.push((mean_label.into(), mean));
    Some(format!("{title}\n\n{}", protocol_tables(&rows)))
}

/// A network's `metrics.json`: every frame's metrics under both protocols and their means.
pub fn metrics_json(per_frame: &[(u32, ProtocolMetrics)]) -> serde_json::Value {
    let rows: Vec<ProtocolMetrics> = per_frame.iter().map(|(_, m)| *m).collect();
    let mean = ProtocolMetrics::mean(&rows);
    serde_json::json!({
        "protocol": Protocol::Reference,
        "frames": per_frame.iter().map(|(f, m)| serde_json::json!({
            "frame": f,
            "metrics": m.reference,
            "metrics_with_sky": m.with_sky,
        })).collect::<Vec<_>>(),
        "mean": mean.map(|m| m.reference),
        "mean_with_sky": mean.map(|m| m.with_sky),
    })
}
