//! The photometric cue of the cascade's stages (`zncc_cue`): at every sample of a stage, the
//! ZNCC of the cameras' own input images (not learnt features) over a window of the stage's
//! grid, averaged over the pairs of cameras that both see the whole window, as ZNCC+SGM
//! matches them (`omnimvs_stereo::Matcher`), appended to the stage's cost volume as one more
//! channel.
//!
//! Why: the learnt features are few (8 channels at stride 2) and the refinement stages tell
//! one index of `N = 192` apart, a third of a stride-2 pixel; plain intensities sampled
//! bilinearly from the full-size image keep the sub-pixel detail the learnt features lose, and
//! cost no learning. The cue carries no gradient (it has no weights, and the hypotheses it is
//! computed at carry none either).
//!
//! Each stage samples the image at a resolution matched to its grid (about two image pixels
//! between neighbouring samples): the coarse stage a quarter-size image, the half-resolution
//! stage a half-size one, the full-resolution stage the input itself (2x2 box averages).
//! For a refinement stage the window's neighbours are taken at their own hypotheses of the same
//! slot (the same offset from their own centres), which are the same depth where the centre
//! map is smooth.

use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_core::interp::grid_sample_plane;
use omnimvs_stereo::params::{COST_SCALE, Directions, cost_units};
use omnimvs_stereo::{CostVolume, SgmParams, ZNCC_VARIANCE_EPS, aggregate, camera_pairs};
use rayon::prelude::*;

use crate::error::NetError;
use crate::pixel::box_sum;
use crate::taps::SweepGrid;
use crate::tensor::with_values;

/// Half the side of the ZNCC window (5 x 5 samples of a stage's grid).
pub const ZNCC_RADIUS: usize = 2;

/// A sample counts as seen by a camera when its bilinear taps inside the image weigh at least
/// this much (all four neighbours inside, up to rounding).
const SEEN_WEIGHT: f32 = 0.999;

/// Every camera's input image at the three resolutions the stages sample: level 0 the input
/// (full-resolution stage), level 1 halved (half-resolution stage), level 2 quartered
/// (coarse stage), by 2x2 box averages.
#[derive(Clone, Debug)]
pub struct ImagePyramid {
    /// `[level][camera]`: row-major values of `sizes[level]`.
    levels: [Vec<Vec<f32>>; 3],
    /// `[rows, cols]` of each level.
    sizes: [[usize; 2]; 3],
}

impl ImagePyramid {
    /// The pyramid of `images`, one row-major `[rows, cols]` image per camera.
    ///
    /// # Errors
    /// [`NetError::Shape`] when there is no image, an image has another size, or the images
    /// are too small to quarter.
    pub fn new(images: Vec<Vec<f32>>, [rows, cols]: [usize; 2]) -> Result<Self, NetError> {
        if images.is_empty()
            || rows < 4
            || cols < 4
            || images.iter().any(|i| i.len() != rows * cols)
        {
            return Err(NetError::Shape {
                what: "images of the photometric cue".into(),
                expected: vec![rows, cols],
                actual: images.iter().map(Vec::len).collect(),
            });
        }
        let half: Vec<Vec<f32>> = images.par_iter().map(|i| halve(i, rows, cols)).collect();
        let [hr, hc] = [rows / 2, cols / 2];
        let quarter: Vec<Vec<f32>> = half.par_iter().map(|i| halve(i, hr, hc)).collect();
        Ok(Self {
            levels: [images, half, quarter],
            sizes: [[rows, cols], [hr, hc], [hr / 2, hc / 2]],
        })
    }

    /// The pyramid of a frame's network inputs, `[1, 1, rows, cols]` per camera (read back
    /// from the device).
    ///
    /// # Errors
    /// [`NetError::Shape`] for inputs of another shape or that cannot be read.
    pub fn from_inputs(images: &[Tensor<4>]) -> Result<Self, NetError> {
        let Some(first) = images.first() else {
            return Err(NetError::Shape {
                what: "images of the photometric cue".into(),
                expected: vec![1],
                actual: vec![0],
            });
        };
        let [_, _, rows, cols] = first.dims();
        let values = images
            .par_iter()
            .map(|image| {
                let dims = image.dims();
                if dims != [1, 1, rows, cols] {
                    return Err(NetError::Shape {
                        what: "input image of the photometric cue".into(),
                        expected: vec![1, 1, rows, cols],
                        actual: dims.to_vec(),
                    });
                }
                with_values(image.clone(), "input image", <[f32]>::to_vec)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(values, [rows, cols])
    }

    /// Number of cameras.
    pub fn num_cameras(&self) -> usize {
        self.levels[0].len()
    }

    /// `[rows, cols]` of `level`.
    pub fn size(&self, level: usize) -> [usize; 2] {
        self.sizes[level]
    }

    /// The cue at the samples of `grids` (one per camera, `K` planes of `rows x cols`
    /// samples each), reading the images of `level`: `K * rows * cols` values in `[-1, 1]`,
    /// 0 where no pair of cameras sees the whole window.
    ///
    /// # Errors
    /// [`NetError::Shape`] when the grids are not one per camera of one size, or `level` is
    /// not 0, 1 or 2.
    pub fn zncc(&self, level: usize, grids: &[SweepGrid]) -> Result<Vec<f32>, NetError> {
        let Some(first) = grids.first() else {
            return Err(NetError::Shape {
                what: "grids of the photometric cue".into(),
                expected: vec![self.num_cameras()],
                actual: vec![0],
            });
        };
        let (k, h, w) = (first.num_spheres, first.height, first.width);
        if level > 2
            || grids.len() != self.num_cameras()
            || grids
                .iter()
                .any(|g| (g.num_spheres, g.height, g.width) != (k, h, w))
        {
            return Err(NetError::Shape {
                what: "grids of the photometric cue (one per camera, one size)".into(),
                expected: vec![self.num_cameras(), k, h, w],
                actual: vec![grids.len(), level],
            });
        }
        let [rows, cols] = self.sizes[level];
        let images = &self.levels[level];
        let plane = h * w;
        let mut out = vec![0f32; k * plane];
        out.par_chunks_mut(plane)
            .enumerate()
            .for_each(|(slot, dst)| {
                // Every camera's samples of this plane and whether it sees them.
                let samples: Vec<(Vec<f32>, Vec<f32>)> = grids
                    .iter()
                    .zip(images)
                    .map(|(grid, image)| {
                        let coords = &grid.coords[2 * slot * plane..2 * (slot + 1) * plane];
                        grid_sample_plane(coords, image, rows, cols, SEEN_WEIGHT)
                    })
                    .collect();
                zncc_plane(&samples, h, w, ZNCC_RADIUS, dst);
            });
        Ok(out)
    }

    /// [`ImagePyramid::zncc`] as a `[1, 1, K, rows, cols]` tensor on `device`, the layout of
    /// a stage's cost volume channels.
    ///
    /// # Errors
    /// See [`ImagePyramid::zncc`].
    pub fn zncc_tensor(
        &self,
        level: usize,
        grids: &[SweepGrid],
        device: &Device,
    ) -> Result<Tensor<5>, NetError> {
        let values = self.zncc(level, grids)?;
        let (k, h, w) = (grids[0].num_spheres, grids[0].height, grids[0].width);
        Ok(Tensor::from_data(
            TensorData::new(values, [1, 1, k, h, w]),
            device,
        ))
    }
}

/// Penalty of the coarse cue's aggregation (`coarse_cue_sgm`) for a change of one depth
/// between neighbours, in cost units `(1 - zncc) / 2`. With [`COARSE_SGM_P2`], the best of
/// the settings tried on things validation frames (`research/cascade.md`).
pub const COARSE_SGM_P1: f32 = 0.05;

/// Penalty of the coarse cue's aggregation for larger changes (see [`COARSE_SGM_P1`]).
pub const COARSE_SGM_P2: f32 = 1.0;

/// A photometric cue aggregated by semi-global matching ([`AggregatedCue::new`]): for every
/// pixel of an `h x w` grid and every plane in the order of its inverse depth, `1 - 2 min(e,
/// 1)` with `e` the plane's mean path cost above the pixel's best (1 at the best plane).
#[derive(Clone, Debug)]
pub struct AggregatedCue {
    /// The planes' inverse depths (index units), ascending.
    pub depths: Vec<f64>,
    /// For each plane in that order, its index in the cue it was made from.
    pub order: Vec<usize>,
    /// `values[pixel * planes + plane]`, in `[-1, 1]`.
    pub values: Vec<f32>,
}

impl AggregatedCue {
    /// The aggregation of `cue`: `depths.len()` maps of `h x w` values in `[-1, 1]`, plane
    /// `j` matched at inverse depth `depths[j]` (index units, any order, repeats allowed).
    /// The costs `(1 - zncc) / 2` of all planes in the order of their depths are aggregated
    /// along 8 paths by semi-global matching with penalties `p1`, `p2` (columns wrap around:
    /// longitude is a ring).
    ///
    /// # Errors
    /// [`NetError::Shape`] when the sizes disagree; [`NetError::Stereo`] when the aggregation
    /// refuses the volume (fewer than 2 planes) or the penalties.
    pub fn new(
        cue: &[f32],
        depths: &[f64],
        [h, w]: [usize; 2],
        [p1, p2]: [f32; 2],
    ) -> Result<Self, NetError> {
        let planes = depths.len();
        let plane = h * w;
        if cue.len() != planes * plane {
            return Err(NetError::Shape {
                what: "photometric cue to aggregate".into(),
                expected: vec![planes, h, w],
                actual: vec![cue.len()],
            });
        }
        let mut order: Vec<usize> = (0..planes).collect();
        order.sort_by(|&a, &b| depths[a].total_cmp(&depths[b]));
        let mut data = vec![0u16; plane * planes];
        for (pixel, costs) in data.chunks_exact_mut(planes).enumerate() {
            for (cost, &j) in costs.iter_mut().zip(&order) {
                let zncc = cue[j * plane + pixel].clamp(-1.0, 1.0);
                *cost = cost_units((1.0 - zncc) * 0.5);
            }
        }
        let summed = aggregate_eight(data, planes, [h, w], [p1, p2])?;
        let unit = 1.0 / (Directions::Eight.count() as f32 * COST_SCALE);
        let mut values = vec![0f32; plane * planes];
        for (sums, out) in summed
            .chunks_exact(planes)
            .zip(values.chunks_exact_mut(planes))
        {
            let best = sums.iter().copied().min().unwrap_or(0);
            for (&sum, value) in sums.iter().zip(out) {
                let excess = f32::from(sum - best) * unit;
                *value = 1.0 - 2.0 * excess.min(1.0);
            }
        }
        Ok(Self {
            depths: order.iter().map(|&j| depths[j]).collect(),
            order,
            values,
        })
    }
}

/// The coarse stage's aggregated cue (`coarse_cue_sgm`) from its ZNCC cue `cue`: `planes`
/// maps of `h x w` values in `[-1, 1]`, plane `j` matched at inverse depth `depths[j]` (index
/// units, any order, repeats allowed), plane `j` belonging to sphere `j % spheres`.
///
/// The cue aggregated with [`COARSE_SGM_P1`], [`COARSE_SGM_P2`] ([`AggregatedCue::new`]);
/// each sphere takes the highest value of its planes: 1 for the best sphere, -1 for one a
/// whole unit of mean path cost worse. `spheres * h * w` values, sphere-major.
///
/// # Errors
/// [`NetError::Shape`] when the sizes disagree; [`NetError::Stereo`] when the aggregation
/// refuses the volume (fewer than 2 planes).
pub fn aggregated_cue(
    cue: &[f32],
    depths: &[f64],
    spheres: usize,
    [h, w]: [usize; 2],
) -> Result<Vec<f32>, NetError> {
    let planes = depths.len();
    let plane = h * w;
    if spheres == 0 || !planes.is_multiple_of(spheres) || cue.len() != planes * plane {
        return Err(NetError::Shape {
            what: "photometric cue to aggregate".into(),
            expected: vec![planes, h, w],
            actual: vec![cue.len(), spheres],
        });
    }
    let aggregated = AggregatedCue::new(cue, depths, [h, w], [COARSE_SGM_P1, COARSE_SGM_P2])?;
    let mut out = vec![-1f32; spheres * plane];
    for (pixel, values) in aggregated.values.chunks_exact(planes).enumerate() {
        for (&value, &j) in values.iter().zip(&aggregated.order) {
            let dst = &mut out[(j % spheres) * plane + pixel];
            *dst = dst.max(value);
        }
    }
    Ok(out)
}

/// A `rows x cols` image halved by 2x2 box averages (a last odd row or column is dropped).
fn halve(image: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    let (hr, hc) = (rows / 2, cols / 2);
    let mut out = Vec::with_capacity(hr * hc);
    for r in 0..hr {
        let top = &image[2 * r * cols..(2 * r + 1) * cols];
        let bottom = &image[(2 * r + 1) * cols..(2 * r + 2) * cols];
        for c in 0..hc {
            out.push(0.25 * (top[2 * c] + top[2 * c + 1] + bottom[2 * c] + bottom[2 * c + 1]));
        }
    }
    out
}

/// One camera's window statistics over a plane of samples.
struct WindowStats<'a> {
    /// The samples themselves.
    values: &'a [f32],
    /// Window mean.
    mean: Vec<f32>,
    /// `1 / std` of the window (variance plus ZNCC+SGM's epsilon).
    inv_std: Vec<f32>,
    /// Whether the camera sees every sample of the window.
    whole: Vec<bool>,
}

impl<'a> WindowStats<'a> {
    fn new(values: &'a [f32], missing: &[f32], counts: &[f32], w: usize, r: usize) -> Self {
        let h = counts.len();
        let squares: Vec<f32> = values.iter().map(|v| v * v).collect();
        let sum = box_sum(values, h, w, r);
        let sq = box_sum(&squares, h, w, r);
        let mut mean = vec![0f32; h * w];
        let mut inv_std = vec![0f32; h * w];
        for (y, &n) in counts.iter().enumerate() {
            for i in y * w..(y + 1) * w {
                mean[i] = sum[i] / n;
                let var = (sq[i] / n - mean[i] * mean[i]).max(0.0);
                inv_std[i] = 1.0 / (var + ZNCC_VARIANCE_EPS).sqrt();
            }
        }
        let whole = box_sum(missing, h, w, r).iter().map(|&m| m < 0.5).collect();
        Self {
            values,
            mean,
            inv_std,
            whole,
        }
    }
}

/// The cue of one plane of samples (`(values, missing)` per camera, `h x w` each) into
/// `out`: mean ZNCC over the camera pairs that both see the whole window, 0 without one.
fn zncc_plane(samples: &[(Vec<f32>, Vec<f32>)], h: usize, w: usize, r: usize, out: &mut [f32]) {
    let counts: Vec<f32> = (0..h).map(|y| window_count(y, h, r)).collect();
    let stats: Vec<WindowStats> = samples
        .iter()
        .map(|(values, missing)| WindowStats::new(values, missing, &counts, w, r))
        .collect();
    let mut total = vec![0f32; h * w];
    let mut pairs = vec![0f32; h * w];
    for (a, b) in camera_pairs(samples.len()) {
        let (sa, sb) = (&stats[a], &stats[b]);
        if !sa.whole.iter().zip(&sb.whole).any(|(&x, &y)| x && y) {
            continue; // the two cameras share no window
        }
        let products: Vec<f32> = sa
            .values
            .iter()
            .zip(sb.values)
            .map(|(x, y)| x * y)
            .collect();
        let prod = box_sum(&products, h, w, r);
        for (y, &n) in counts.iter().enumerate() {
            for i in y * w..(y + 1) * w {
                if sa.whole[i] && sb.whole[i] {
                    let cov = prod[i] / n - sa.mean[i] * sb.mean[i];
                    total[i] += (cov * sa.inv_std[i] * sb.inv_std[i]).clamp(-1.0, 1.0);
                    pairs[i] += 1.0;
                }
            }
        }
    }
    for ((o, &t), &p) in out.iter_mut().zip(&total).zip(&pairs) {
        *o = if p > 0.0 { t / p } else { 0.0 };
    }
}

/// Samples in the window of a pixel of row `y` (rows clipped to the grid).
fn window_count(y: usize, h: usize, r: usize) -> f32 {
    let rows = (y + r).min(h - 1) - y.saturating_sub(r) + 1;
    (rows * (2 * r + 1)) as f32
}

/// Semi-global aggregation along 8 paths (columns wrapping: longitude is a ring) of a cost
/// volume of `planes` costs per pixel in the 16-bit units of `omnimvs_stereo`
/// ([`cost_units`], pixel-major, `h x w` pixels), penalties `[p1, p2]` in the same units: the
/// sums over the paths, pixel-major. What the aggregated photometric cues
/// ([`AggregatedCue`]) are made by.
///
/// # Errors
/// [`NetError::Stereo`] when the aggregation refuses the penalties or the volume (fewer than 2
/// planes).
pub(crate) fn aggregate_eight(
    data: Vec<u16>,
    planes: usize,
    [h, w]: [usize; 2],
    [p1, p2]: [f32; 2],
) -> Result<Vec<u16>, NetError> {
    let volume = CostVolume {
        height: h,
        width: w,
        ndepth: planes,
        data,
    };
    let params = SgmParams {
        p1,
        p2,
        directions: Directions::Eight,
        ..SgmParams::default()
    };
    Ok(aggregate(&volume, &params)?.0.data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_views_score_one_and_unseen_windows_zero() {
        let (h, w) = (6, 8);
        let texture: Vec<f32> = (0..h * w).map(|i| ((i * 7919) % 13) as f32).collect();
        let seen = vec![0f32; h * w];
        let mut out = vec![0f32; h * w];
        // Two cameras seeing the same texture, a third its negative, seen everywhere.
        let negative: Vec<f32> = texture.iter().map(|v| -2.0 * v + 3.0).collect();
        let samples = vec![
            (texture.clone(), seen.clone()),
            (texture.clone(), seen.clone()),
            (negative, seen.clone()),
        ];
        zncc_plane(&samples[..2], h, w, 1, &mut out);
        assert!(out.iter().all(|&z| z > 0.99), "{out:?}");
        // Pairs (0, 1) = 1, (0, 2) = (1, 2) = -1: mean -1/3.
        zncc_plane(&samples, h, w, 1, &mut out);
        assert!(out.iter().all(|&z| (z + 1.0 / 3.0).abs() < 0.01), "{out:?}");
        // A camera that misses one sample: windows containing it have no pair.
        let mut missing = seen;
        missing[2 * w + 3] = 1.0;
        let samples = vec![(texture.clone(), vec![0.0; h * w]), (texture, missing)];
        zncc_plane(&samples, h, w, 1, &mut out);
        assert_eq!(out[2 * w + 3], 0.0);
        assert_eq!(out[w + 4], 0.0);
        assert!(out[5 * w + 7] > 0.99);
    }

    #[test]
    fn the_aggregated_cue_fills_a_weak_pixel_from_its_neighbours_and_checks_sizes() {
        // 3 spheres of 2 depths each (depths in no order), a 4 x 8 grid: every pixel matches
        // best at depth 4.0 (plane 4, sphere 1) but one, whose own best is depth 0.0 (sphere 0)
        // by a little; the paths outvote it.
        let (h, w) = (4, 8);
        let depths = [0.0, 4.0, 8.0, 1.0, 5.0, 9.0];
        let plane = h * w;
        let mut cue = vec![-0.5f32; depths.len() * plane];
        let odd = 2 * w + 3;
        for pixel in 0..plane {
            cue[4 * plane + pixel] = if pixel == odd { 0.3 } else { 0.9 };
        }
        cue[odd] = 0.4;
        let out = aggregated_cue(&cue, &depths, 3, [h, w]).unwrap();
        assert_eq!(out.len(), 3 * plane);
        for pixel in 0..plane {
            let values: Vec<f32> = (0..3).map(|s| out[s * plane + pixel]).collect();
            assert_eq!(values[1], 1.0, "pixel {pixel}: {values:?}");
            assert!(
                values[0] < 1.0 && values[2] < 1.0,
                "pixel {pixel}: {values:?}"
            );
            assert!(values.iter().all(|v| (-1.0..=1.0).contains(v)));
        }
        // The raw cue's best at the odd pixel was sphere 0.
        assert!(cue[odd] > cue[4 * plane + odd]);
        assert!(aggregated_cue(&cue, &depths, 4, [h, w]).is_err());
        assert!(aggregated_cue(&cue[1..], &depths, 3, [h, w]).is_err());
        assert!(aggregated_cue(&cue, &depths, 0, [h, w]).is_err());
    }

    #[test]
    fn the_aggregated_cue_orders_its_planes_by_depth() {
        // Two pixels, three planes at depths 2, 0, 4 (stored in that order): at each pixel the
        // planes in depth order, ascending.
        let (h, w) = (1, 2);
        let depths = [2.0, 0.0, 4.0];
        // Pixel 0 best at depth 2, pixel 1 best at depth 4, clearly.
        let cue = vec![0.9, -0.5, -0.5, -0.5, -0.5, 0.9];
        let aggregated = AggregatedCue::new(&cue, &depths, [h, w], [0.0, 0.0]).unwrap();
        assert_eq!(aggregated.depths, vec![0.0, 2.0, 4.0]);
        assert_eq!(aggregated.order, vec![1, 0, 2]);
        // No penalties: each pixel its own cost; the best plane reads 1, the others 1 - 2e with
        // e = 0.7 (the cost difference), so -0.4.
        let near = |a: f32, b: f32| (a - b).abs() < 1e-2;
        let row = |p: usize| &aggregated.values[p * 3..p * 3 + 3];
        assert!(near(row(0)[1], 1.0) && near(row(0)[0], -0.4) && near(row(0)[2], -0.4));
        assert!(near(row(1)[2], 1.0) && near(row(1)[0], -0.4) && near(row(1)[1], -0.4));
        assert!(AggregatedCue::new(&cue[1..], &depths, [h, w], [0.0, 0.0]).is_err());
    }

    #[test]
    fn the_pyramid_halves_by_box_averages() {
        let image: Vec<f32> = (0..8 * 8).map(|i| i as f32).collect();
        let pyramid = ImagePyramid::new(vec![image], [8, 8]).unwrap();
        assert_eq!(pyramid.size(1), [4, 4]);
        assert_eq!(pyramid.size(2), [2, 2]);
        // Level 1 (0, 0): mean of 0, 1, 8, 9.
        assert_eq!(pyramid.levels[1][0][0], 4.5);
        // Level 2 (0, 0): mean of the 4 x 4 block at the origin.
        assert_eq!(pyramid.levels[2][0][0], 13.5);
        assert!(ImagePyramid::new(vec![vec![0.0; 10]], [8, 8]).is_err());
    }
}
