//! The files of one frame's estimate, named `%05d<suffix>` in an output folder.

use std::path::{Path, PathBuf};

use omnimvs_camera::Rig;
use omnimvs_camera::ValidityMask;
use omnimvs_core::{ColourPlanes, GrayImage};
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::estimate::DepthEstimate;
use omnimvs_data::gt::{GroundTruth, write_f32_tiff};
use omnimvs_data::image_io::write_png_u8;
use omnimvs_sweep::{
    ColourPanorama, InvDepthSource, Panorama, compose_colour_panorama, compose_panorama,
};

use super::pictures::{error_map, fisheye_strip, gray_to_rgb, point_cloud};
use crate::ply::{ColoredPoint, write_ply};
use omnimvs_data::DataError;

/// `dir/%05d<suffix>`, the path of one of a frame's files.
pub fn frame_path(dir: &Path, frame: u32, suffix: &str) -> PathBuf {
    dir.join(format!("{frame:05}{suffix}"))
}

/// Writes the maps of an estimate as f32 TIFFs on its grid: `.tiff` (inverse depth, 1/m),
/// `_index.tiff` (hypothesis index), `_confidence.tiff` and `_confidence.png` (gray, 0..1
/// as 0..255) when it has a confidence, `_entropy.tiff` when it has an entropy, `_spread.tiff`
/// when it has a spread.
///
/// # Errors
/// [`DataError`] naming a file that cannot be written.
pub fn write_maps(dir: &Path, frame: u32, est: &DepthEstimate) -> Result<(), DataError> {
    let (w, h) = (est.spec.width(), est.spec.height());
    let path = |suffix| frame_path(dir, frame, suffix);
    write_f32_tiff(&path(".tiff"), w, h, &est.inv_depth)?;
    write_f32_tiff(&path("_index.tiff"), w, h, &est.index)?;
    if let Some(entropy) = &est.entropy {
        write_f32_tiff(&path("_entropy.tiff"), w, h, entropy)?;
    }
    if let Some(spread) = &est.spread {
        write_f32_tiff(&path("_spread.tiff"), w, h, spread)?;
    }
    if let Some(conf) = &est.confidence {
        write_f32_tiff(&path("_confidence.tiff"), w, h, conf)?;
        let gray: Vec<u8> = conf
            .iter()
            .map(|&c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect();
        write_png_u8(&path("_confidence.png"), w, h, 1, &gray)?;
    }
    Ok(())
}

/// The `q`-quantile of the finite values (0 when there is none).
pub fn quantile(values: &[f32], q: f64) -> f32 {
    let mut v: Vec<f32> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Writes `_invdepth.png`, the inverse depth colour-mapped (turbo, near = warm) between the
/// frame's 1st and 99th percentiles; returns those two inverse depths (1/m).
///
/// # Errors
/// [`DataError`] naming a file that cannot be written.
pub fn write_percentile_png(
    dir: &Path,
    frame: u32,
    est: &DepthEstimate,
) -> Result<[f32; 2], DataError> {
    let lo = quantile(&est.inv_depth, 0.01);
    let hi = quantile(&est.inv_depth, 0.99);
    let rgb = colorize(
        &est.inv_depth,
        f64::from(lo),
        f64::from(hi),
        Colormap::Turbo,
        None,
    );
    let path = frame_path(dir, frame, "_invdepth.png");
    write_png_u8(&path, est.spec.width(), est.spec.height(), 3, &rgb)?;
    Ok([lo, hi])
}

/// What a frame's pictures show besides the estimate: the rig, its images and masks, and
/// the ground truth on the estimate's grid when there is one.
#[derive(Clone, Copy)]
pub struct FrameScene<'a> {
    pub rig: &'a Rig,
    /// The frame's gray images, rig order.
    pub images: &'a [GrayImage],
    /// The cameras' validity masks.
    pub masks: &'a [ValidityMask],
    /// The frame's colour images, rig order, when they are in colour
    /// ([`omnimvs_data::Dataset::read_frame_and_colour`]); `None` for gray ones.
    pub colour: Option<&'a [ColourPlanes]>,
}

impl FrameScene<'_> {
    /// The gray panorama seen at the estimate's inverse depth, on its grid.
    ///
    /// # Errors
    /// [`DataError`] for images that do not fit the rig.
    pub fn panorama(&self, est: &DepthEstimate) -> Result<Panorama, DataError> {
        Ok(compose_panorama(
            self.rig,
            &est.spec.grid,
            self.images,
            Some(self.masks),
            InvDepthSource::Map(&est.inv_depth),
        )?)
    }

    /// The colour panorama seen at the estimate's inverse depth, on its grid; `None` when
    /// the scene has no colour images.
    ///
    /// # Errors
    /// [`DataError`] for images that do not fit the rig.
    pub fn colour_panorama(
        &self,
        est: &DepthEstimate,
    ) -> Result<Option<ColourPanorama>, DataError> {
        let Some(colour) = self.colour else {
            return Ok(None);
        };
        Ok(Some(compose_colour_panorama(
            self.rig,
            &est.spec.grid,
            colour,
            Some(self.masks),
            InvDepthSource::Map(&est.inv_depth),
        )?))
    }

    /// The estimate's point cloud coloured by the panorama at its depth: the colour panorama
    /// when the scene has colour images, else `gray` ([`Self::panorama`]).
    ///
    /// # Errors
    /// [`DataError`] for images that do not fit the rig.
    pub fn point_cloud(
        &self,
        est: &DepthEstimate,
        gray: &Panorama,
    ) -> Result<Vec<ColoredPoint>, DataError> {
        let (grid, inv_depth) = (&est.spec.grid, &est.inv_depth);
        Ok(match self.colour_panorama(est)? {
            Some(pano) => {
                let [r, g, b] = &pano.image.planes;
                point_cloud(grid, inv_depth, [&r.data, &g.data, &b.data])
            }
            None => {
                let v = &gray.image.data;
                point_cloud(grid, inv_depth, [v, v, v])
            }
        })
    }

    /// Writes [`Self::point_cloud`] of frame `frame` as `dir/%05d.ply`.
    ///
    /// # Errors
    /// As [`Self::point_cloud`]; a file that cannot be written.
    pub fn write_point_cloud(
        &self,
        dir: &Path,
        frame: u32,
        est: &DepthEstimate,
        gray: &Panorama,
    ) -> Result<(), DataError> {
        let points = self.point_cloud(est, gray)?;
        write_ply(&frame_path(dir, frame, ".ply"), &points)
    }
}

/// Writes `.png` (inverse depth colour-mapped on `[0, 1/min_depth]`), `_vis.png` (rows:
/// inputs, panorama at the estimated depth, depth, entropy, and the error when `truth` is
/// given) and with `ply` a point cloud `.ply` coloured by the panorama (in colour when the
/// scene has colour images; [`FrameScene::point_cloud`]).
///
/// # Errors
/// [`DataError`] for images that do not fit the rig or a file that cannot be written.
pub fn write_depth_pictures(
    dir: &Path,
    frame: u32,
    est: &DepthEstimate,
    scene: FrameScene<'_>,
    truth: Option<&GroundTruth>,
    ply: bool,
) -> Result<(), DataError> {
    let (w, h) = (est.spec.width(), est.spec.height());
    let ndepth = est.spec.ndepth();
    let max_inv = est.spec.hypotheses.max_inv_depth();
    let depth_rgb = colorize(&est.inv_depth, 0.0, max_inv, Colormap::Turbo, None);
    write_png_u8(&frame_path(dir, frame, ".png"), w, h, 3, &depth_rgb)?;
    let pano = scene.panorama(est)?;
    let mut rows: Vec<Vec<u8>> = vec![
        fisheye_strip(scene.images, w),
        gray_to_rgb(&pano.image),
        depth_rgb,
    ];
    if let Some(entropy) = &est.entropy {
        rows.push(colorize(
            entropy,
            0.0,
            (ndepth as f64).ln(),
            Colormap::Inferno,
            None,
        ));
    }
    if let Some(truth) = truth {
        rows.push(error_map(&est.index, truth, ndepth));
    }
    let composite: Vec<u8> = rows.concat();
    let vis = frame_path(dir, frame, "_vis.png");
    write_png_u8(&vis, w, composite.len() / (3 * w), 3, &composite)?;
    if ply {
        scene.write_point_cloud(dir, frame, est, &pano)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_skip_non_finite_values() {
        let v = [f32::NAN, 3.0, 1.0, 2.0, f32::INFINITY];
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert_eq!(quantile(&v, 1.0), 3.0);
        assert_eq!(quantile(&[], 0.5), 0.0);
    }
}
