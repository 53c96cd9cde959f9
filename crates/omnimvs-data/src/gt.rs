//! Ground-truth inverse depth (1/m) on the equirectangular grid: the three
//! encodings of `FORMATS.md`, centre cropping, and the invalid-pixel rule.

use std::io::Cursor;
use std::path::Path;

use omnimvs_camera::nalgebra::Rotation3;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use tiff::decoder::{Decoder, DecodingResult};
use tiff::encoder::{Compression, DeflateLevel, TiffEncoder, colortype};

use crate::DataError;

/// Width of the published ground-truth panoramas.
pub const GT_WIDTH: usize = 640;

/// Scale of the released 16-bit PNG encoding: `invdepth = v / 65500 / 0.55`.
pub const PNG16_MAX_INV_DEPTH: f64 = 1.0 / 0.55;

/// An inverse-depth map (1/m), row-major; 0 = at infinity.
#[derive(Debug, Clone, PartialEq)]
pub struct InvDepthMap {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl InvDepthMap {
    /// The latitude range `±phi_deg` that an equirectangular map of this
    /// shape covers (square pixels: `180 * height / width`).
    pub fn phi_deg(&self) -> f64 {
        180.0 * self.height as f64 / self.width as f64
    }

    /// The middle `height` rows, as the reference crops (start row
    /// `round((H - h) / 2)`, ties to even like Python's `round`).
    ///
    /// # Errors
    /// [`SweepError::Mismatch`](omnimvs_sweep::SweepError::Mismatch) when `height` exceeds the map's height.
    pub fn crop_rows_centered(&self, height: usize) -> Result<Self, DataError> {
        if height > self.height {
            return Err(DataError::mismatch(
                "ground-truth crop height",
                format!("at most {} rows", self.height),
                height,
            ));
        }
        let start = ((self.height - height) as f64 / 2.0).round_ties_even() as usize;
        let data = self.data[start * self.width..(start + height) * self.width].to_vec();
        Ok(Self {
            width: self.width,
            height,
            data,
        })
    }
}

/// Reads an inverse-depth file by its extension: `.tif`/`.tiff` (the f32
/// page of a possibly multi-page file), `.png` (16-bit released encoding),
/// anything else raw little-endian f32 of width [`GT_WIDTH`].
///
/// # Errors
/// [`DataError`] naming the file: unreadable, no f32 page, wrong bit depth,
/// or a raw size that is not a whole number of rows.
pub fn read_inv_depth(path: &Path) -> Result<InvDepthMap, DataError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "tif" | "tiff" => read_tiff_f32(path),
        "png" => read_png16(path),
        _ => read_raw_f32(path, GT_WIDTH),
    }
}

/// Reads the f32 page of a TIFF file (the reference writes an 8-bit RGB
/// thumbnail first, then the f32 data).
///
/// # Errors
/// [`DataError::Format`] when no page holds single-channel f32 data.
pub fn read_tiff_f32(path: &Path) -> Result<InvDepthMap, DataError> {
    let bytes = std::fs::read(path).map_err(|e| DataError::io(path, e))?;
    let bad = |e: tiff::TiffError| DataError::format(path, format!("cannot decode TIFF: {e}"));
    let mut dec = Decoder::new(Cursor::new(bytes)).map_err(bad)?;
    loop {
        let (w, h) = dec.dimensions().map_err(bad)?;
        if let Ok(tiff::ColorType::Gray(32)) = dec.colortype()
            && let DecodingResult::F32(data) = dec.read_image().map_err(bad)?
        {
            return Ok(InvDepthMap {
                width: w as usize,
                height: h as usize,
                data,
            });
        }
        if !dec.more_images() {
            return Err(DataError::format(
                path,
                "no single-channel 32-bit float page (expected the f32 inverse depth)",
            ));
        }
        dec.next_image().map_err(bad)?;
    }
}

fn read_png16(path: &Path) -> Result<InvDepthMap, DataError> {
    let bytes = std::fs::read(path).map_err(|e| DataError::io(path, e))?;
    let img = image::load_from_memory(&bytes).map_err(|source| DataError::Image {
        path: path.to_path_buf(),
        source,
    })?;
    let image::DynamicImage::ImageLuma16(g) = img else {
        return Err(DataError::format(
            path,
            format!(
                "expected a 16-bit gray PNG (released inverse-depth encoding), found {:?}",
                img.color()
            ),
        ));
    };
    let (w, h) = (g.width() as usize, g.height() as usize);
    let data = g
        .into_raw()
        .into_iter()
        .map(|v| (f64::from(v) / 65500.0 * PNG16_MAX_INV_DEPTH) as f32)
        .collect();
    Ok(InvDepthMap {
        width: w,
        height: h,
        data,
    })
}

/// Reads raw little-endian f32 rows of `width` values.
///
/// # Errors
/// [`DataError::Format`] when the size is not a whole number of rows.
pub fn read_raw_f32(path: &Path, width: usize) -> Result<InvDepthMap, DataError> {
    let bytes = std::fs::read(path).map_err(|e| DataError::io(path, e))?;
    let row_bytes = width * 4;
    if bytes.is_empty() || bytes.len() % row_bytes != 0 {
        return Err(DataError::format(
            path,
            format!(
                "raw f32 file of {} bytes: expected a whole number of rows of {width} floats ({row_bytes} bytes)",
                bytes.len()
            ),
        ));
    }
    let data = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok(InvDepthMap {
        width,
        height: bytes.len() / row_bytes,
        data,
    })
}

/// Checks that `data` holds a `width x height` map before it is written to `path`.
fn check_map_len(path: &Path, width: usize, height: usize, data: &[f32]) -> Result<(), DataError> {
    if data.len() == width * height {
        return Ok(());
    }
    Err(DataError::mismatch(
        format!("{}: map length", path.display()),
        width * height,
        data.len(),
    ))
}

/// Writes an f32 map as a single-page, deflate-compressed TIFF, atomically.
///
/// # Errors
/// [`DataError`] naming the file.
pub fn write_f32_tiff(
    path: &Path,
    width: usize,
    height: usize,
    data: &[f32],
) -> Result<(), DataError> {
    write_tiff_pages(path, width, height, None, data)
}

/// Writes a TIFF, atomically: the 8-bit RGB `picture` of the map first when given
/// (uncompressed), then the `f32` values (deflate-compressed).
fn write_tiff_pages(
    path: &Path,
    width: usize,
    height: usize,
    picture: Option<&[u8]>,
    data: &[f32],
) -> Result<(), DataError> {
    check_map_len(path, width, height, data)?;
    let mut buf = Cursor::new(Vec::new());
    let bad = |e: tiff::TiffError| DataError::format(path, format!("cannot encode TIFF: {e}"));
    let mut encoder = TiffEncoder::new(&mut buf).map_err(bad)?;
    if let Some(picture) = picture {
        encoder
            .write_image::<colortype::RGB8>(width as u32, height as u32, picture)
            .map_err(bad)?;
    }
    encoder
        .with_compression(Compression::Deflate(DeflateLevel::Balanced))
        .write_image::<colortype::Gray32Float>(width as u32, height as u32, data)
        .map_err(bad)?;
    omnimvs_core::fs::write_atomic(path, buf.get_ref()).map_err(|e| DataError::io(path, e))
}

/// Writes a ground-truth inverse-depth panorama (1/m) the way the released datasets store it,
/// which is what the reference implementation's reader expects: a two-page TIFF, page 0 an
/// 8-bit RGB picture of the map (turbo colour map, 0 to the largest value), page 1 the `f32`
/// values (deflate-compressed). Readers take the floating-point page ([`read_inv_depth`]).
///
/// # Errors
/// [`DataError`] naming the file.
pub fn write_gt_tiff(
    path: &Path,
    width: usize,
    height: usize,
    data: &[f32],
) -> Result<(), DataError> {
    check_map_len(path, width, height, data)?;
    let max = data
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0f32, f32::max);
    let picture = crate::colormap::colorize(
        data,
        0.0,
        if max > 0.0 { f64::from(max) } else { 1.0 },
        crate::colormap::Colormap::Turbo,
        None,
    );
    write_tiff_pages(path, width, height, Some(&picture), data)
}

/// Writes an inverse-depth map (1/m) as an f32 TIFF, atomically.
///
/// # Errors
/// As [`write_f32_tiff`].
pub fn write_inv_depth_tiff(path: &Path, map: &InvDepthMap) -> Result<(), DataError> {
    write_f32_tiff(path, map.width, map.height, &map.data)
}

/// Ground truth as hypothesis indices, with the evaluation mask.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    pub width: usize,
    pub height: usize,
    /// Fractional index `n*` of every pixel.
    pub index: Vec<f32>,
    /// Whether the pixel counts in training and evaluation.
    pub valid: Vec<bool>,
}

/// Inverse depths below this (farther than 1 km) count as "infinite".
pub const FINITE_INV_DEPTH: f32 = 1e-3;

/// Converts a (cropped) inverse-depth map to indices and applies the
/// reference's invalid-pixel rule: an "infinite" pixel (inverse depth below
/// [`FINITE_INV_DEPTH`]) inside a hole that a 5x5 binary closing of the
/// finite-depth mask fills is invalid (it is noise, not sky); every valid
/// pixel has `0 <= n* <= N`. Inverse depth 0 (sky) maps to index 0 and is
/// valid: the ground truth of training, and of the `with-sky` evaluation
/// protocol. The reference's `evalError` does not score sky (its index is
/// `(0 - d_0) / step`, just below 0 there); [`EvalTruth`] carries the sky mask
/// that the `reference` protocol (`omnimvs_eval::metrics::Protocol`) leaves out.
pub fn ground_truth_index(map: &InvDepthMap, hyps: &InvDepthHypotheses) -> GroundTruth {
    let (w, h) = (map.width, map.height);
    let finite: Vec<bool> = map.data.iter().map(|&d| d >= FINITE_INV_DEPTH).collect();
    let closed = binary_closing_5x5(&finite, w, h);
    let n = hyps.count as f32;
    let mut index = Vec::with_capacity(w * h);
    let mut valid = Vec::with_capacity(w * h);
    for i in 0..w * h {
        // Sky is stored as inverse depth 0, which sits f64::EPSILON below d_0
        // (index -1e-14): that is index 0, not "behind the farthest sphere".
        let idx = hyps.index(f64::from(map.data[i])).max(0.0) as f32;
        let hole = !finite[i] && closed[i];
        index.push(idx);
        valid.push(!hole && idx.is_finite() && (0.0..=n).contains(&idx));
    }
    GroundTruth {
        width: w,
        height: h,
        index,
        valid,
    }
}

/// Ground truth on the rays of `grid`, turned by `source_from_grid` (identity for the map's
/// own frame, a rig rotation for augmented training samples): the indices and the validity
/// of [`ground_truth_index`], computed at the map's own resolution (the reference's rule),
/// sampled at the nearest pixel along `source_from_grid * ray`. Rays outside the map's
/// latitudes are invalid. Evaluation (`infer`, `sgm`, `eval`) and training use this one
/// sampling, so their metrics agree.
pub fn sample_ground_truth(
    map: &InvDepthMap,
    hyps: &InvDepthHypotheses,
    grid: &EquirectGrid,
    source_from_grid: &Rotation3<f64>,
) -> Result<GroundTruth, DataError> {
    let full = ground_truth_index(map, hyps);
    let mut index = Vec::with_capacity(grid.len());
    let mut valid = Vec::with_capacity(grid.len());
    for at in nearest_pixels(map, grid, source_from_grid)? {
        match at {
            Some(at) => {
                index.push(full.index[at]);
                valid.push(full.valid[at]);
            }
            None => {
                index.push(0.0);
                valid.push(false);
            }
        }
    }
    Ok(GroundTruth {
        width: grid.width,
        height: grid.height,
        index,
        valid,
    })
}

/// The pixel of `map` nearest to `source_from_grid * ray` for every ray of `grid`, `None`
/// outside the map's latitudes: the one sampling of [`sample_ground_truth`] and
/// [`sample_eval_truth`].
fn nearest_pixels(
    map: &InvDepthMap,
    grid: &EquirectGrid,
    source_from_grid: &Rotation3<f64>,
) -> Result<Vec<Option<usize>>, DataError> {
    let source = EquirectGrid::new(map.height, map.width, map.phi_deg())?;
    Ok(grid
        .rays()
        .iter()
        .map(|ray| {
            let (row, col) = source.position_of(&(source_from_grid * ray));
            let row = row.round();
            (row >= 0.0 && row <= (map.height - 1) as f64)
                .then(|| row as usize * map.width + (col.round() as usize) % map.width)
        })
        .collect())
}

/// Whether a ground-truth inverse depth (1/m) is sky in the reference's convention: below
/// `d_0` (the sphere at infinity, `f64::EPSILON`), so that its index `(d - d_0) / step` is
/// negative and the reference's `evalError` (`0 <= n* <= N`) does not score it. Inverse
/// depth 0, the encoding of sky in every ground-truth format, is sky.
pub fn is_sky(inv_depth: f32, hyps: &InvDepthHypotheses) -> bool {
    f64::from(inv_depth) < hyps.min_inv_depth()
}

/// The ground truth of one frame for evaluation under both protocols
/// (`omnimvs_eval::metrics::Protocol`): `gt` is the ground truth of training and of the
/// `with-sky` protocol (sky valid at index 0), `sky` marks the pixels that are sky
/// ([`is_sky`]), which the `reference` protocol does not score.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalTruth {
    /// Indices and validity, exactly as [`ground_truth_index`] / [`sample_ground_truth`].
    pub gt: GroundTruth,
    /// Whether each pixel is sky (inverse depth below `d_0`), row-major like `gt`.
    pub sky: Vec<bool>,
}

/// [`ground_truth_index`] of a (cropped) map together with its sky mask.
pub fn eval_truth_index(map: &InvDepthMap, hyps: &InvDepthHypotheses) -> EvalTruth {
    EvalTruth {
        gt: ground_truth_index(map, hyps),
        sky: map.data.iter().map(|&d| is_sky(d, hyps)).collect(),
    }
}

/// [`sample_ground_truth`] together with the sky mask sampled at the same pixels.
///
/// # Errors
/// As [`sample_ground_truth`].
pub fn sample_eval_truth(
    map: &InvDepthMap,
    hyps: &InvDepthHypotheses,
    grid: &EquirectGrid,
    source_from_grid: &Rotation3<f64>,
) -> Result<EvalTruth, DataError> {
    let gt = sample_ground_truth(map, hyps, grid, source_from_grid)?;
    let sky = nearest_pixels(map, grid, source_from_grid)?
        .into_iter()
        .map(|at| at.is_some_and(|at| is_sky(map.data[at], hyps)))
        .collect();
    Ok(EvalTruth { gt, sky })
}

/// The evaluation ground truth of `map` on an output `grid`: a grid at the map's own width
/// with square pixels (`phi_deg = 180 height / width`, e.g. 160x640 at ±45 degrees for a
/// 640-wide map) gets the middle rows cropped and the invalid rule applied to the crop,
/// exactly as the reference's `loadGTInvdepthIndex`; any other grid samples the indices, the
/// validity (computed at full resolution) and the sky mask at its rays
/// ([`sample_eval_truth`]). The caller checks that the grid's latitudes lie inside the map's.
///
/// # Errors
/// A crop taller than the map.
pub fn eval_truth_on_grid(
    map: &InvDepthMap,
    hyps: &InvDepthHypotheses,
    grid: &EquirectGrid,
) -> Result<EvalTruth, DataError> {
    let square_phi_deg = 180.0 * grid.height as f64 / grid.width as f64;
    if map.width == grid.width && (grid.phi_deg - square_phi_deg).abs() < 1e-9 {
        let cropped = map.crop_rows_centered(grid.height)?;
        return Ok(eval_truth_index(&cropped, hyps));
    }
    sample_eval_truth(map, hyps, grid, &Rotation3::identity())
}

/// One pass of a 5-wide max (dilate) or min (erode) along rows or columns,
/// treating pixels outside the image as `false` (scipy's `border_value=0`).
fn pass(src: &[bool], w: usize, h: usize, horizontal: bool, dilate: bool) -> Vec<bool> {
    let mut out = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut acc = !dilate;
            for k in -2i64..=2 {
                let (xx, yy) = if horizontal {
                    (x as i64 + k, y as i64)
                } else {
                    (x as i64, y as i64 + k)
                };
                let v = xx >= 0
                    && yy >= 0
                    && (xx as usize) < w
                    && (yy as usize) < h
                    && src[yy as usize * w + xx as usize];
                acc = if dilate { acc || v } else { acc && v };
            }
            out[y * w + x] = acc;
        }
    }
    out
}

/// `scipy.ndimage.binary_closing(mask, ones((5, 5)))`: dilation then
/// erosion, both with outside pixels `false`.
pub fn binary_closing_5x5(mask: &[bool], w: usize, h: usize) -> Vec<bool> {
    let d = pass(&pass(mask, w, h, true, true), w, h, false, true);
    pass(&pass(&d, w, h, true, false), w, h, false, false)
}

#[cfg(test)]
mod tests {

    #[test]
    fn ground_truth_tiff_has_the_released_two_pages() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gt.tiff");
        let data: Vec<f32> = (0..6 * 4).map(|i| i as f32 * 0.01).collect();
        write_gt_tiff(&path, 6, 4, &data).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let mut dec = tiff::decoder::Decoder::new(std::io::Cursor::new(bytes)).unwrap();
        assert_eq!(dec.colortype().unwrap(), tiff::ColorType::RGB(8));
        assert_eq!(dec.dimensions().unwrap(), (6, 4));
        assert!(dec.more_images());
        dec.next_image().unwrap();
        assert_eq!(dec.colortype().unwrap(), tiff::ColorType::Gray(32));
        assert!(!dec.more_images());
        let map = read_inv_depth(&path).unwrap();
        assert_eq!((map.width, map.height), (6, 4));
        assert_eq!(map.data, data);
    }

    use super::*;

    #[test]
    fn closing_fills_small_holes_but_not_near_borders() {
        let (w, h) = (12, 12);
        let mut m = vec![true; w * h];
        m[6 * w + 6] = false; // an interior hole
        m[0] = false; // a corner pixel
        let c = binary_closing_5x5(&m, w, h);
        assert!(c[6 * w + 6], "interior hole is closed");
        // Erosion with a zero border clears everything within 2 px of the edge.
        assert!(!c[0] && !c[w + 1] && c[2 * w + 2]);
    }

    #[test]
    fn invalid_rule_marks_holes_not_sky() {
        let hyps = InvDepthHypotheses::new(192, 0.5).unwrap();
        let (w, h) = (20, 20);
        // Top half sky (0), bottom half at 2 m, one noisy zero inside.
        let mut data = vec![0f32; w * h];
        for v in &mut data[10 * w..] {
            *v = 0.5;
        }
        data[15 * w + 10] = 0.0;
        let gt = ground_truth_index(
            &InvDepthMap {
                width: w,
                height: h,
                data,
            },
            &hyps,
        );
        assert!(gt.valid[2 * w + 10], "sky is valid");
        assert!(!gt.valid[15 * w + 10], "noise hole is invalid");
        assert!(gt.valid[15 * w + 11]);
        assert!((gt.index[15 * w + 11] - 0.5 / (2.0 / 191.0)).abs() < 1e-3);
    }

    #[test]
    fn sampling_applies_the_rule_at_full_resolution() {
        let hyps = InvDepthHypotheses::new(64, 0.5).unwrap();
        let (w, h) = (640, 320);
        let source = EquirectGrid::new(h, w, 90.0).unwrap();
        let grid = EquirectGrid::new(32, 128, 45.0).unwrap();
        let hit = |r: f64, c: f64| {
            let (row, col) = source.position_of(&grid.ray(r, c));
            (row.round() as usize, col.round() as usize % w)
        };
        let mut data = vec![0.5f32; w * h];
        // A 12x12 patch of sky: wider than the 5x5 closing, so sky (valid) at full
        // resolution, though a single pixel once sampled at the coarse grid.
        let (pr, pc) = hit(10.0, 30.0);
        for r in pr - 6..pr + 6 {
            for c in pc - 6..pc + 6 {
                data[r * w + c] = 0.0;
            }
        }
        // One noisy zero: a hole, invalid.
        let (nr, nc) = hit(20.0, 90.0);
        data[nr * w + nc] = 0.0;
        let map = InvDepthMap {
            width: w,
            height: h,
            data,
        };
        let gt = sample_ground_truth(&map, &hyps, &grid, &Rotation3::identity()).unwrap();
        assert_eq!((gt.height, gt.width), (32, 128));
        assert!(gt.valid[10 * 128 + 30], "the sky patch stays valid");
        assert_eq!(gt.index[10 * 128 + 30], 0.0);
        assert!(!gt.valid[20 * 128 + 90], "the noise hole is invalid");
        assert!(gt.valid[20 * 128 + 91]);
        // A grid taller than the map: rows outside its latitudes are invalid.
        let tall = EquirectGrid::new(64, 128, 90.0).unwrap();
        let narrow = InvDepthMap {
            width: w,
            height: 160,
            data: vec![0.5; w * 160],
        };
        let gt = sample_ground_truth(&narrow, &hyps, &tall, &Rotation3::identity()).unwrap();
        assert!(!gt.valid[0] && gt.valid[32 * 128]);
    }

    #[test]
    fn sky_is_below_the_farthest_sphere_and_follows_the_sampling() {
        let hyps = InvDepthHypotheses::new(192, 0.5).unwrap();
        assert!(is_sky(0.0, &hyps) && is_sky(-1.0, &hyps));
        // 1e-10 1/m (10,000,000 km) has a positive index: the reference scores it.
        assert!(!is_sky(1e-10, &hyps) && !is_sky(0.5, &hyps) && !is_sky(f32::NAN, &hyps));
        // Top half sky, bottom half at 2 m, on the 320x640 grid of the ground truth.
        let (w, h) = (640, 320);
        let data = (0..w * h)
            .map(|i| if i / w < h / 2 { 0.0 } else { 0.5 })
            .collect();
        let map = InvDepthMap {
            width: w,
            height: h,
            data,
        };
        // The paper's grid crops the middle rows; the sky mask is the crop's.
        let crop =
            eval_truth_on_grid(&map, &hyps, &EquirectGrid::new(160, 640, 45.0).unwrap()).unwrap();
        assert!(crop.sky[79 * w] && !crop.sky[80 * w]);
        assert_eq!(
            crop.gt,
            ground_truth_index(&map.crop_rows_centered(160).unwrap(), &hyps)
        );
        // The first row is sky (scored with sky only), the last row scene.
        assert!(crop.gt.valid[0] && crop.sky[0]);
        assert!(crop.gt.valid[159 * w] && !crop.sky[159 * w]);
        // A coarser grid samples the same rays for the indices, the validity and the sky.
        let grid = EquirectGrid::new(32, 128, 45.0).unwrap();
        let sampled = eval_truth_on_grid(&map, &hyps, &grid).unwrap();
        assert_eq!(
            sampled.gt,
            sample_ground_truth(&map, &hyps, &grid, &Rotation3::identity()).unwrap()
        );
        for (i, &sky) in sampled.sky.iter().enumerate() {
            assert_eq!(sky, i / 128 < 16, "pixel {i}");
        }
    }

    #[test]
    fn crop_is_centered() {
        let map = InvDepthMap {
            width: 1,
            height: 320,
            data: (0..320).map(|v| v as f32).collect(),
        };
        let c = map.crop_rows_centered(160).unwrap();
        assert_eq!(c.data[0], 80.0);
        assert!(map.crop_rows_centered(400).is_err());
    }
}
