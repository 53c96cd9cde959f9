//! How well a depth map explains the images, without ground truth: the cross-camera
//! photometric difference.
//!
//! Every output pixel with a depth is a point in the rig frame. Projected into every camera that
//! sees it, it samples that camera's gray value (bilinear). Where the depth is right the cameras
//! see the same surface point and agree. The measure is the median absolute difference over
//! every pair of cameras that see a point, divided by the standard deviation of every gray value
//! sampled: lower is better. Pairs that share 100 points or fewer are left out. It is the
//! reading of `../shared/tools/omni_np.py`'s `consistency`, for every camera model.

use std::path::{Path, PathBuf};

use nalgebra::Point3;
use omnimvs_camera::Rig;
use omnimvs_core::GrayImage;
use omnimvs_core::interp::sample_inside_f64;
use omnimvs_data::DataError;
use omnimvs_sweep::EquirectGrid;
use serde::Serialize;

use crate::output::report::{write_json, write_text};

/// The fewest points two cameras must share for their differences to count.
pub const MIN_SHARED_POINTS: usize = 100;

/// The smallest inverse depth (1/m) that counts as a depth; below it (and NaN) a pixel has none.
const MIN_INV_DEPTH: f32 = 1e-6;

/// The cross-camera photometric difference of `inv_depth` (1/m on `grid`, row-major) with the
/// frame's `images` (rig order). `None` when no two cameras share more than
/// [`MIN_SHARED_POINTS`] points, or when the sizes do not match.
pub fn photometric_difference(
    rig: &Rig,
    images: &[GrayImage],
    grid: &EquirectGrid,
    inv_depth: &[f32],
) -> Option<f64> {
    if images.len() != rig.len() || inv_depth.len() != grid.height * grid.width {
        return None;
    }
    let points: Vec<Point3<f64>> = inv_depth
        .iter()
        .enumerate()
        .filter(|&(_, &d)| d > MIN_INV_DEPTH)
        .map(|(i, &d)| {
            let ray = grid.ray((i / grid.width) as f64, (i % grid.width) as f64);
            Point3::from(ray / f64::from(d))
        })
        .collect();
    // Each camera's gray value at every point it sees.
    let samples: Vec<Vec<Option<f64>>> = rig
        .cameras
        .iter()
        .zip(images)
        .map(|(camera, image)| {
            points
                .iter()
                .map(|p| {
                    let px = camera.project_rig(p)?;
                    sample_inside_f64(image, px.col, px.row)
                })
                .collect()
        })
        .collect();
    let mut diffs = Vec::new();
    for a in 0..samples.len() {
        for b in a + 1..samples.len() {
            let pair: Vec<f64> = samples[a]
                .iter()
                .zip(&samples[b])
                .filter_map(|(va, vb)| Some((va.as_ref()? - vb.as_ref()?).abs()))
                .collect();
            if pair.len() > MIN_SHARED_POINTS {
                diffs.extend(pair);
            }
        }
    }
    if diffs.is_empty() {
        return None;
    }
    let values: Vec<f64> = samples.iter().flatten().flatten().copied().collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let std = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    Some(median(&mut diffs) / (std + 1e-9))
}

/// One method's photometric differences, frame by frame.
#[derive(Debug, Clone, Serialize)]
pub struct PhotometricRow {
    pub method: String,
    /// `(frame, difference)`; `None` where no two cameras shared enough points.
    pub per_frame: Vec<(u32, Option<f64>)>,
    /// The mean over the frames that have a value.
    pub mean: Option<f64>,
    /// The method's estimate per frame, seconds (0 for a constant depth).
    pub seconds_per_frame: f64,
}

impl PhotometricRow {
    /// The row of `method` from its per-frame values.
    pub fn new(
        method: impl Into<String>,
        per_frame: Vec<(u32, Option<f64>)>,
        seconds_per_frame: f64,
    ) -> Self {
        let values: Vec<f64> = per_frame.iter().filter_map(|&(_, v)| v).collect();
        let mean = (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64);
        Self {
            method: method.into(),
            per_frame,
            mean,
            seconds_per_frame,
        }
    }
}

/// The photometric evaluation of methods on frames without ground truth (`eval.json`).
#[derive(Debug, Serialize)]
pub struct PhotometricReport {
    pub dataset: PathBuf,
    pub frames: Vec<u32>,
    /// What the values are.
    pub measure: &'static str,
    pub methods: Vec<PhotometricRow>,
}

impl PhotometricReport {
    /// The report of `methods` on `frames` of `dataset`.
    pub fn new(dataset: &Path, frames: Vec<u32>, methods: Vec<PhotometricRow>) -> Self {
        Self {
            dataset: dataset.to_path_buf(),
            frames,
            measure: "cross-camera photometric difference: median absolute gray difference over \
                      camera pairs seeing a point / standard deviation of the gray values \
                      sampled (lower is better)",
            methods,
        }
    }

    /// The table: one row per method, one column per frame and the mean (`eval.md`).
    pub fn table(&self) -> String {
        let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
        let mut text = format!(
            "{}: cross-camera photometric difference of each depth map (lower is better; no \
             ground truth)\n\n| method |",
            self.dataset.display()
        );
        for f in &self.frames {
            text.push_str(&format!(" frame {f} |"));
        }
        text.push_str(" mean |\n|---|");
        for _ in &self.frames {
            text.push_str("---:|");
        }
        text.push_str("---:|\n");
        for row in &self.methods {
            text.push_str(&format!("| {} |", row.method));
            for (_, v) in &row.per_frame {
                text.push_str(&format!(" {} |", fmt(*v)));
            }
            text.push_str(&format!(" {} |\n", fmt(row.mean)));
        }
        text
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

/// The median of `values` (not empty), the mean of the middle two for an even count, as numpy.
fn median(values: &mut [f64]) -> f64 {
    let n = values.len();
    let mid = n / 2;
    let (_, upper, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    let upper = *upper;
    if n % 2 == 1 {
        return upper;
    }
    let lower = values[..mid]
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    (lower + upper) / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_is_numpys() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
    }
}
