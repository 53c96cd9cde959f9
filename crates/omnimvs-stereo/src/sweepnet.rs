//! The SweepNet-style learned matching cost (Won et al., ICRA 2019): a network that
//! looks at the spherically warped images of all cameras around a sphere point and predicts
//! its matching cost.
//!
//! SweepNet warps the fisheye images onto every sweep sphere and lets a CNN turn the warped
//! images into a cost map per sphere. Ours, sized for a CPU, splits that network in two:
//!
//! * a fixed first stage ([`band_features`]) computed with running sums on the warped images
//!   of each sphere ([`FeatureLayout`]): for each window size of a [`FeatureSpec`], every
//!   camera pair's ZNCC and whether both windows are complete, every camera's texture
//!   (`ln(variance + eps) / 4`) and whether its window is complete; then every pair's
//!   difference of normalised centre samples and, optionally, the best ZNCC of the shifted
//!   windows (58 numbers for four cameras, three window sizes and the shifted windows);
//! * a learned head ([`SweepCostHead`], in practice the [`Mlp`] that `omnimvs-net` trains)
//!   that turns those numbers into the cost in `[0, 1]`. It can learn what an average of pair
//!   costs cannot: to distrust a pair where one camera is occluded or a window is flat, to
//!   weigh wide and narrow baselines differently, to be sure where all pairs agree.
//!
//! Where no camera pair sees the window the cost is [`NO_PAIR_COST`], as for ZNCC.

use std::fmt::Debug;
use std::ops::Range;

use omnimvs_sweep::SphereProjector;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};

use crate::cost::{NO_PAIR_COST, ZNCC_VARIANCE_EPS, camera_pairs};
use crate::learned::{SphereCost, learned_cost_volume};
use crate::params::SweepStep;
use crate::{CameraView, CostTimings, CostVolume, StereoError};

/// Output rows computed together (the warped band holds `BAND` rows and the reach of the
/// widest window, [`FeatureSpec`]'s `reach`, above and below).
const BAND: usize = 16;

/// Layout of one feature vector for `ncam` cameras and `scales` window sizes: per window
/// size `[zncc of each pair, pair complete (0/1), texture of each camera, camera complete
/// (0/1)]`, then per pair the difference of the two cameras' normalised centre samples
/// (normalised by the first window size's mean and deviation; 0 where incomplete).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FeatureLayout {
    pub ncam: usize,
    pub scales: usize,
    /// Whether the shifted-window block follows ([`FeatureSpec::shifted`]).
    pub shifted: bool,
}

/// Which window features a head reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FeatureSpec {
    /// Half sides of the windows, first one first (4: the paper's 9x9); the first one also
    /// normalises the centre samples.
    pub radii: Vec<usize>,
    /// Per pair, the best ZNCC of the first window size among the 8 windows shifted by its
    /// half side around the pixel (and whether any was complete): shiftable windows, the
    /// classical remedy against foreground fattening at occlusion edges.
    pub shifted: bool,
}

impl FeatureSpec {
    /// The layout of these features for `ncam` cameras.
    pub fn layout(&self, ncam: usize) -> FeatureLayout {
        FeatureLayout {
            ncam,
            scales: self.radii.len(),
            shifted: self.shifted,
        }
    }

    /// Rows above and below a band that its features read.
    fn reach(&self) -> usize {
        let widest = self.radii.iter().copied().max().unwrap_or(0);
        let shift = if self.shifted {
            2 * self.radii.first().copied().unwrap_or(0)
        } else {
            0
        };
        widest.max(shift)
    }
}

impl FeatureLayout {
    pub fn pairs(&self) -> usize {
        self.ncam * (self.ncam - 1) / 2
    }
    fn block(&self) -> usize {
        2 * self.pairs() + 2 * self.ncam
    }
    pub fn zncc(&self, scale: usize, pair: usize) -> usize {
        scale * self.block() + pair
    }
    pub fn pair_complete(&self, scale: usize, pair: usize) -> usize {
        scale * self.block() + self.pairs() + pair
    }
    pub fn texture(&self, scale: usize, cam: usize) -> usize {
        scale * self.block() + 2 * self.pairs() + cam
    }
    pub fn camera_complete(&self, scale: usize, cam: usize) -> usize {
        scale * self.block() + 2 * self.pairs() + self.ncam + cam
    }
    pub fn center_difference(&self, pair: usize) -> usize {
        self.scales * self.block() + pair
    }
    pub fn shifted_zncc(&self, pair: usize) -> usize {
        self.scales * self.block() + self.pairs() + pair
    }
    pub fn shifted_complete(&self, pair: usize) -> usize {
        self.scales * self.block() + 2 * self.pairs() + pair
    }
    pub fn dim(&self) -> usize {
        let shifted = if self.shifted { 2 * self.pairs() } else { 0 };
        self.scales * self.block() + self.pairs() + shifted
    }

    /// The plain ZNCC cost of one feature vector: `(1 - zncc) / 2` of the first window size
    /// averaged over the complete pairs, [`NO_PAIR_COST`] without any (what the ZNCC cost
    /// volume holds, up to the order of its sums).
    pub fn zncc_cost(&self, features: &[f32]) -> f32 {
        let (mut sum, mut count) = (0f32, 0f32);
        for p in 0..self.pairs() {
            if features[self.pair_complete(0, p)] > 0.5 {
                sum += 0.5 * (1.0 - features[self.zncc(0, p)]);
                count += 1.0;
            }
        }
        if count > 0.0 {
            sum / count
        } else {
            NO_PAIR_COST
        }
    }
}

/// The learned part of the cost: feature vectors in, costs in `[0, 1]` out.
pub trait SweepCostHead: Debug + Send + Sync {
    /// The method's name in reports (`SweepNet+SGM`).
    fn method_name(&self) -> &str;

    /// Length of one feature vector it expects.
    fn input_dim(&self) -> usize;

    /// The window features it reads.
    fn features(&self) -> &FeatureSpec;

    /// The costs of `out.len()` feature vectors laid end to end in `features`.
    fn costs(&self, features: &[f32], out: &mut [f32]);

    /// The share of the plain 9x9 ZNCC cost ([`FeatureLayout::zncc_cost`]) in the cost that
    /// SGM gets, `(1 - w) * learned + w * zncc`, in `[0, 1]` (0: the learned cost alone).
    fn zncc_weight(&self) -> f32 {
        0.0
    }
}

/// One fully connected layer, `weight[o * inputs + i]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Dense {
    pub inputs: usize,
    pub outputs: usize,
    pub weight: Vec<f32>,
    pub bias: Vec<f32>,
}

/// A multi-layer perceptron: ReLU between the layers, a sigmoid after the last (one output):
/// the [`SweepCostHead`] that `omnimvs-net`'s SweepNet trains, run here without a tensor
/// library.
#[derive(Debug, Clone, PartialEq)]
pub struct Mlp {
    name: String,
    /// The window features it reads ([`SweepCostHead::features`]).
    spec: FeatureSpec,
    layers: Vec<Dense>,
    /// Each layer's weights as `[input][output]`.
    transposed: Vec<Vec<f32>>,
    /// [`SweepCostHead::zncc_weight`].
    zncc_weight: f32,
}

impl Mlp {
    /// Checks that the layers chain and end in one output.
    ///
    /// # Errors
    /// [`StereoError::Volume`] naming the first layer that does not fit.
    pub fn new(name: &str, spec: FeatureSpec, layers: Vec<Dense>) -> Result<Self, StereoError> {
        let bad = |msg: String| StereoError::Volume(format!("{name} head: {msg}"));
        if layers.is_empty() {
            return Err(bad("expected at least one layer".into()));
        }
        if spec.radii.is_empty() || spec.radii.contains(&0) {
            return Err(bad(
                "expected at least one window half side, each >= 1".into()
            ));
        }
        for (k, l) in layers.iter().enumerate() {
            if l.weight.len() != l.inputs * l.outputs || l.bias.len() != l.outputs {
                return Err(bad(format!(
                    "layer {k}: weight {} and bias {} values, expected {}x{} and {}",
                    l.weight.len(),
                    l.bias.len(),
                    l.outputs,
                    l.inputs,
                    l.outputs
                )));
            }
            if k > 0 && layers[k - 1].outputs != l.inputs {
                return Err(bad(format!(
                    "layer {k} takes {} inputs, the layer before gives {}",
                    l.inputs,
                    layers[k - 1].outputs
                )));
            }
        }
        if layers[layers.len() - 1].outputs != 1 {
            return Err(bad("expected one output (the cost)".into()));
        }
        let transposed = layers
            .iter()
            .map(|l| {
                let mut t = vec![0f32; l.inputs * l.outputs];
                for o in 0..l.outputs {
                    for i in 0..l.inputs {
                        t[i * l.outputs + o] = l.weight[o * l.inputs + i];
                    }
                }
                t
            })
            .collect();
        Ok(Self {
            name: name.into(),
            spec,
            layers,
            transposed,
            zncc_weight: 0.0,
        })
    }

    /// The same head with `weight` of the plain ZNCC cost mixed into its cost
    /// ([`SweepCostHead::zncc_weight`]).
    ///
    /// # Errors
    /// [`StereoError::Parameter`] for a weight outside `[0, 1]`.
    pub fn with_zncc_weight(mut self, weight: f32) -> Result<Self, StereoError> {
        if !(0.0..=1.0).contains(&weight) {
            return Err(StereoError::Parameter {
                name: "zncc_weight",
                value: weight.to_string(),
                expected: "a share in [0, 1]",
            });
        }
        self.zncc_weight = weight;
        Ok(self)
    }
}

impl SweepCostHead for Mlp {
    fn method_name(&self) -> &str {
        &self.name
    }

    fn input_dim(&self) -> usize {
        self.layers[0].inputs
    }

    fn features(&self) -> &FeatureSpec {
        &self.spec
    }

    fn zncc_weight(&self) -> f32 {
        self.zncc_weight
    }

    fn costs(&self, features: &[f32], out: &mut [f32]) {
        let widest = self.layers.iter().map(|l| l.outputs).max().unwrap_or(1);
        let (mut a, mut b) = (vec![0f32; widest], vec![0f32; widest]);
        let dim = self.input_dim();
        let last = self.layers.len() - 1;
        for (x, o) in features.chunks_exact(dim).zip(out.iter_mut()) {
            let mut input: &[f32] = x;
            for (k, (l, wt)) in self.layers.iter().zip(&self.transposed).enumerate() {
                // y = bias + sum_i x_i W[i][..]: the inner loop runs over the outputs,
                // contiguous in the transposed weights, and vectorises.
                let y = &mut a[..l.outputs];
                y.copy_from_slice(&l.bias);
                for (&xi, row) in input.iter().zip(wt.chunks_exact(l.outputs)) {
                    for (yj, &wij) in y.iter_mut().zip(row) {
                        *yj += xi * wij;
                    }
                }
                if k < last {
                    y.iter_mut().for_each(|v| *v = v.max(0.0));
                }
                std::mem::swap(&mut a, &mut b);
                input = &b[..l.outputs];
            }
            *o = 1.0 / (1.0 + (-input[0]).exp());
        }
    }
}

/// Per-thread buffers of [`band_features`].
#[derive(Debug, Default)]
pub struct BandScratch {
    values: Vec<f32>,
    missing: Vec<f32>,
    pos_col: Vec<f32>,
    pos_row: Vec<f32>,
    table_pos: Vec<f32>,
    /// `[quantity][warped row + 1][col]`: sums of the warped rows above.
    prefix: Vec<f32>,
    /// `[col]`: one quantity's sum over an output row's window rows.
    colsum: Vec<f32>,
    /// `[quantity][col]`: whole-window sums of one output row.
    boxsum: Vec<f32>,
    mean: Vec<f32>,
    inv_std: Vec<f32>,
    /// `[row][pair][col]`: ZNCC of the first window size, for the shifted windows.
    shifted: Vec<f32>,
}

/// The feature vectors of output rows `rows` (all columns) on the sphere of inverse depth
/// `inv_depth` (1/m) into `out`, `[(row - rows.start) * width + col][dim]` with the
/// layout of `spec` for `views.len()` cameras. Windows are clipped at the top and bottom of
/// the grid and wrap round in longitude.
#[allow(clippy::too_many_arguments)]
pub fn band_features(
    grid: &EquirectGrid,
    projectors: &[SphereProjector],
    views: &[CameraView],
    spec: &FeatureSpec,
    rows: Range<usize>,
    inv_depth: f32,
    scratch: &mut BandScratch,
    out: &mut [f32],
) {
    let (w, h) = (grid.width, grid.height);
    let ncam = views.len();
    let pairs = camera_pairs(ncam);
    let reach = spec.reach();
    let band = Band {
        w,
        h,
        ncam,
        w0: rows.start.saturating_sub(reach),
        nwarp: (rows.end + reach).min(h) - rows.start.saturating_sub(reach),
        nq: 3 * ncam + pairs.len(),
    };
    let s = scratch;
    warp_band(&band, projectors, views, inv_depth, s);
    prefix_sums(&band, &pairs, s);
    s.colsum.resize(w, 0.0);
    s.boxsum.resize(band.nq * w, 0.0);
    s.mean.resize(ncam * w, 0.0);
    s.inv_std.resize(ncam * w, 0.0);
    let mut current = WindowStats {
        mean: vec![0f32; ncam],
        inv_std: vec![0f32; ncam],
    };
    // Shiftable windows: the first window size's ZNCC of every pair on the band's rows and
    // the rows one shift above and below it (NaN where a window is incomplete).
    let shift = spec.radii[0];
    let e0 = rows.start.saturating_sub(shift);
    if spec.shifted {
        shifted_znccs(&band, &pairs, shift, e0..(rows.end + shift).min(h), s);
    }
    let layout = spec.layout(ncam);
    let dim = layout.dim();
    for (o, row) in rows.clone().enumerate() {
        let out_row = &mut out[o * w * dim..][..w * dim];
        for (scale, &radius) in spec.radii.iter().enumerate() {
            window_features(
                &band,
                &pairs,
                &layout,
                (row, scale, radius),
                s,
                &mut current,
                out_row,
            );
        }
        center_differences(&band, &pairs, &layout, row, s, out_row);
        if spec.shifted {
            best_shifted(&band, &pairs, &layout, (row, shift, e0), s, out_row);
        }
    }
}

/// The shape of one band of [`band_features`]: the grid's `w` x `h`, `ncam` cameras, the
/// `nwarp` warped rows from grid row `w0` that its windows reach, and `nq` summed quantities
/// (per camera the sum, sum of squares and missing count; per pair the product sum).
struct Band {
    w: usize,
    h: usize,
    ncam: usize,
    w0: usize,
    nwarp: usize,
    nq: usize,
}

/// One window's mean and inverse standard deviation (0 where the window is incomplete), per
/// camera.
struct WindowStats {
    mean: Vec<f32>,
    inv_std: Vec<f32>,
}

/// Every camera's image warped onto the band's rows of the sphere: `s.values` and
/// `s.missing` (1 where the camera does not see the point), `[cam][warped row][col]`.
fn warp_band(
    band: &Band,
    projectors: &[SphereProjector],
    views: &[CameraView],
    inv_depth: f32,
    s: &mut BandScratch,
) {
    let (w, nwarp) = (band.w, band.nwarp);
    s.values.resize(band.ncam * nwarp * w, 0.0);
    s.missing.resize(band.ncam * nwarp * w, 0.0);
    s.pos_col.resize(w, 0.0);
    s.pos_row.resize(w, 0.0);
    s.table_pos.resize(w, 0.0);
    for cam in 0..band.ncam {
        for r in 0..nwarp {
            projectors[cam].project_run(
                (band.w0 + r) * w,
                inv_depth,
                &mut s.pos_col,
                &mut s.pos_row,
                &mut s.table_pos,
            );
            let at = (cam * nwarp + r) * w;
            for x in 0..w {
                (s.values[at + x], s.missing[at + x]) =
                    match views[cam].sample(s.pos_col[x], s.pos_row[x]) {
                        Some(v) => (v, 0.0),
                        None => (0.0, 1.0),
                    };
            }
        }
    }
}

/// The quantities' sums down the warped rows into `s.prefix`, so that any window's rows are
/// one difference.
fn prefix_sums(band: &Band, pairs: &[(usize, usize)], s: &mut BandScratch) {
    let (w, nwarp, ncam, nq) = (band.w, band.nwarp, band.ncam, band.nq);
    let stride = (nwarp + 1) * w;
    s.prefix.clear();
    s.prefix.resize(nq * stride, 0.0);
    for k in 0..nwarp {
        for q in 0..nq {
            let at = q * stride + k * w;
            let (above, below) = s.prefix[at..at + 2 * w].split_at_mut(w);
            if q >= 3 * ncam {
                let (a, b) = pairs[q - 3 * ncam];
                let va = &s.values[(a * nwarp + k) * w..][..w];
                let vb = &s.values[(b * nwarp + k) * w..][..w];
                for x in 0..w {
                    below[x] = above[x] + va[x] * vb[x];
                }
                continue;
            }
            let cam = q % ncam;
            let v = &s.values[(cam * nwarp + k) * w..][..w];
            let m = &s.missing[(cam * nwarp + k) * w..][..w];
            match q / ncam {
                0 => (0..w).for_each(|x| below[x] = above[x] + v[x]),
                1 => (0..w).for_each(|x| below[x] = above[x] + v[x] * v[x]),
                _ => (0..w).for_each(|x| below[x] = above[x] + m[x]),
            }
        }
    }
}

/// The ZNCC of every pair over the `shift`-radius window of grid rows `extended` into
/// `s.shifted`, `[row - extended.start][pair][col]` (NaN where a window is incomplete).
fn shifted_znccs(
    band: &Band,
    pairs: &[(usize, usize)],
    shift: usize,
    extended: Range<usize>,
    s: &mut BandScratch,
) {
    let (w, np) = (band.w, pairs.len());
    let e0 = extended.start;
    s.shifted.resize(extended.len() * np * w, f32::NAN);
    for er in extended {
        let inv_n = window_sums(s, er, shift, band.w0, band.h, w, band.nq);
        for (p, &pair) in pairs.iter().enumerate() {
            let dst = &mut s.shifted[((er - e0) * np + p) * w..][..w];
            for (x, d) in dst.iter_mut().enumerate() {
                *d = boxsum_zncc(&s.boxsum, w, band.ncam, inv_n, p, pair, x).unwrap_or(f32::NAN);
            }
        }
    }
}

/// The features of window size `scale` (radius `radius`) of grid row `row` into `out_row`
/// (`[col][dim]`): every camera's texture and completeness, every pair's ZNCC and
/// completeness. The first size's statistics are kept in `s.mean` and `s.inv_std` for the
/// centre differences.
fn window_features(
    band: &Band,
    pairs: &[(usize, usize)],
    layout: &FeatureLayout,
    (row, scale, radius): (usize, usize, usize),
    s: &mut BandScratch,
    current: &mut WindowStats,
    out_row: &mut [f32],
) {
    let (w, ncam) = (band.w, band.ncam);
    let dim = layout.dim();
    let inv_n = window_sums(s, row, radius, band.w0, band.h, w, band.nq);
    for x in 0..w {
        let q = |quantity: usize| s.boxsum[quantity * w + x];
        let f = &mut out_row[x * dim..][..dim];
        for cam in 0..ncam {
            let mu = q(cam) * inv_n;
            let var = (q(ncam + cam) * inv_n - mu * mu).max(0.0);
            let complete = q(2 * ncam + cam) < 0.5;
            current.mean[cam] = mu;
            current.inv_std[cam] = if complete {
                1.0 / (var + ZNCC_VARIANCE_EPS).sqrt()
            } else {
                0.0
            };
            f[layout.texture(scale, cam)] = if complete {
                0.25 * (var + ZNCC_VARIANCE_EPS).ln()
            } else {
                0.0
            };
            f[layout.camera_complete(scale, cam)] = if complete { 1.0 } else { 0.0 };
        }
        for (p, &(a, b)) in pairs.iter().enumerate() {
            let norm = current.inv_std[a] * current.inv_std[b];
            let used = norm > 0.0;
            let cov = q(3 * ncam + p) * inv_n - current.mean[a] * current.mean[b];
            f[layout.zncc(scale, p)] = if used {
                (cov * norm).clamp(-1.0, 1.0)
            } else {
                0.0
            };
            f[layout.pair_complete(scale, p)] = if used { 1.0 } else { 0.0 };
        }
        if scale == 0 {
            for cam in 0..ncam {
                s.mean[cam * w + x] = current.mean[cam];
                s.inv_std[cam * w + x] = current.inv_std[cam];
            }
        }
    }
}

/// The pairs' differences of their centre samples of grid row `row`, normalised by the first
/// window's statistics, into `out_row`.
fn center_differences(
    band: &Band,
    pairs: &[(usize, usize)],
    layout: &FeatureLayout,
    row: usize,
    s: &BandScratch,
    out_row: &mut [f32],
) {
    let (w, nwarp) = (band.w, band.nwarp);
    let dim = layout.dim();
    let k = row - band.w0;
    for x in 0..w {
        let f = &mut out_row[x * dim..][..dim];
        for (p, &(a, b)) in pairs.iter().enumerate() {
            let (ia, ib) = (s.inv_std[a * w + x], s.inv_std[b * w + x]);
            f[layout.center_difference(p)] = if ia > 0.0 && ib > 0.0 {
                let za = (s.values[(a * nwarp + k) * w + x] - s.mean[a * w + x]) * ia;
                let zb = (s.values[(b * nwarp + k) * w + x] - s.mean[b * w + x]) * ib;
                za - zb
            } else {
                0.0
            };
        }
    }
}

/// Every pair's best ZNCC among the 8 windows shifted by `shift` around grid row `row`'s
/// (from `s.shifted`, whose rows start at `e0`) into `out_row`, with whether any was seen.
fn best_shifted(
    band: &Band,
    pairs: &[(usize, usize)],
    layout: &FeatureLayout,
    (row, shift, e0): (usize, usize, usize),
    s: &BandScratch,
    out_row: &mut [f32],
) {
    let (w, h, np) = (band.w, band.h, pairs.len());
    let dim = layout.dim();
    for x in 0..w {
        let f = &mut out_row[x * dim..][..dim];
        for p in 0..np {
            let mut best = f32::NEG_INFINITY;
            for dy in [-1isize, 0, 1] {
                let Some(r) = row.checked_add_signed(dy * shift as isize) else {
                    continue;
                };
                if r >= h {
                    continue;
                }
                let line = &s.shifted[((r - e0) * np + p) * w..][..w];
                for dx in [w - shift, 0, shift] {
                    if dy == 0 && dx == 0 {
                        continue;
                    }
                    let v = line[(x + dx) % w];
                    if v > best {
                        best = v;
                    }
                }
            }
            let seen = best.is_finite();
            f[layout.shifted_zncc(p)] = if seen { best } else { 0.0 };
            f[layout.shifted_complete(p)] = if seen { 1.0 } else { 0.0 };
        }
    }
}

/// Sums of every quantity over the `(2 radius + 1)`-square window of each column of grid row
/// `row` into `s.boxsum` (from the prefix sums of the warped rows starting at `w0`); returns
/// one over the number of samples in a window.
fn window_sums(
    s: &mut BandScratch,
    row: usize,
    radius: usize,
    w0: usize,
    h: usize,
    w: usize,
    nq: usize,
) -> f32 {
    let stride = s.prefix.len() / nq;
    let (r0, r1) = (row.saturating_sub(radius), (row + radius + 1).min(h));
    for q in 0..nq {
        let top = &s.prefix[q * stride + (r0 - w0) * w..][..w];
        let bottom = &s.prefix[q * stride + (r1 - w0) * w..][..w];
        for ((c, &b), &t) in s.colsum.iter_mut().zip(bottom).zip(top) {
            *c = b - t;
        }
        // Window sums along the row, round the ring.
        let dst = &mut s.boxsum[q * w..][..w];
        let src = &s.colsum;
        let mut acc: f32 = (0..2 * radius + 1).map(|k| src[(k + w - radius) % w]).sum();
        for (x, d) in dst.iter_mut().enumerate() {
            *d = acc;
            acc += src[(x + radius + 1) % w] - src[(x + w - radius) % w];
        }
    }
    1.0 / ((r1 - r0) * (2 * radius + 1)) as f32
}

/// The ZNCC of camera pair `p` = `(a, b)` at column `x` from [`window_sums`]' sums; `None`
/// when either window misses a sample.
fn boxsum_zncc(
    boxsum: &[f32],
    w: usize,
    ncam: usize,
    inv_n: f32,
    p: usize,
    (a, b): (usize, usize),
    x: usize,
) -> Option<f32> {
    let q = |k: usize| boxsum[k * w + x];
    if q(2 * ncam + a) >= 0.5 || q(2 * ncam + b) >= 0.5 {
        return None;
    }
    let (ma, mb) = (q(a) * inv_n, q(b) * inv_n);
    let va = (q(ncam + a) * inv_n - ma * ma).max(0.0) + ZNCC_VARIANCE_EPS;
    let vb = (q(ncam + b) * inv_n - mb * mb).max(0.0) + ZNCC_VARIANCE_EPS;
    let cov = q(3 * ncam + p) * inv_n - ma * mb;
    Some((cov / (va * vb).sqrt()).clamp(-1.0, 1.0))
}

/// Whether any camera pair sees the window of a feature vector.
pub fn any_pair(features: &[f32], layout: FeatureLayout) -> bool {
    (0..layout.pairs()).any(|p| features[layout.pair_complete(0, p)] > 0.5)
}

/// A head's cost on the window features of the warped images, mixed with the plain ZNCC cost
/// by its [`SweepCostHead::zncc_weight`].
struct HeadCost<'a> {
    grid: &'a EquirectGrid,
    projectors: &'a [SphereProjector],
    views: &'a [CameraView],
    head: &'a dyn SweepCostHead,
    layout: FeatureLayout,
}

/// Per-thread buffers of [`HeadCost`]: the band's feature vectors and their scratch.
#[derive(Default)]
struct HeadScratch {
    band: BandScratch,
    features: Vec<f32>,
}

impl SphereCost for HeadCost<'_> {
    const ROWS: usize = BAND;
    type Scratch = HeadScratch;

    fn costs(&self, rows: Range<usize>, inv_depth: f32, s: &mut HeadScratch, out: &mut [f32]) {
        let (layout, dim) = (self.layout, self.layout.dim());
        s.features.resize(out.len() * dim, 0.0);
        band_features(
            self.grid,
            self.projectors,
            self.views,
            self.head.features(),
            rows,
            inv_depth,
            &mut s.band,
            &mut s.features,
        );
        self.head.costs(&s.features, out);
        let zncc_weight = self.head.zncc_weight();
        for (f, c) in s.features.chunks_exact(dim).zip(out.iter_mut()) {
            *c = if any_pair(f, layout) {
                let learned = c.clamp(0.0, 1.0);
                if zncc_weight > 0.0 {
                    (1.0 - zncc_weight) * learned + zncc_weight * layout.zncc_cost(f)
                } else {
                    learned
                }
            } else {
                NO_PAIR_COST
            };
        }
    }
}

/// The cost volume of a frame by a learned head on the warped images' window features.
///
/// # Errors
/// [`StereoError::CountMismatch`] for views and projectors of different counts,
/// [`StereoError::Volume`] for a head that expects another feature length.
pub fn sweep_cost_volume(
    grid: &EquirectGrid,
    projectors: &[SphereProjector],
    views: &[CameraView],
    head: &dyn SweepCostHead,
    hyps: &InvDepthHypotheses,
    sweep: SweepStep,
) -> Result<(CostVolume, CostTimings), StereoError> {
    let ncam = views.len();
    if ncam != projectors.len() {
        return Err(StereoError::CountMismatch {
            what: "camera views",
            expected: projectors.len(),
            found: ncam,
        });
    }
    let layout = head.features().layout(ncam);
    let dim = layout.dim();
    if head.input_dim() != dim {
        return Err(StereoError::Volume(format!(
            "{}: the network takes {} features per point, a rig of {ncam} cameras gives {dim}",
            head.method_name(),
            head.input_dim()
        )));
    }
    let cost = HeadCost {
        grid,
        projectors,
        views,
        head,
        layout,
    };
    Ok(learned_cost_volume(grid, hyps, sweep, &cost))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mlp_checks_its_layers_and_computes_relu_then_sigmoid() {
        let l1 = Dense {
            inputs: 2,
            outputs: 2,
            weight: vec![1.0, 0.0, 0.0, -1.0],
            bias: vec![0.0, 0.5],
        };
        let l2 = Dense {
            inputs: 2,
            outputs: 1,
            weight: vec![2.0, 1.0],
            bias: vec![-1.0],
        };
        let spec = FeatureSpec {
            radii: vec![4],
            shifted: false,
        };
        let mlp = Mlp::new("test", spec.clone(), vec![l1.clone(), l2.clone()]).unwrap();
        let mut out = [0f32; 2];
        mlp.costs(&[1.0, 2.0, -3.0, 0.25], &mut out);
        // (1, 2): hidden (1, relu(-1.5) = 0) -> 2 - 1 = 1; (-3, 0.25): (0, 0.25) -> -0.75.
        let sig = |v: f32| 1.0 / (1.0 + (-v).exp());
        assert!((out[0] - sig(1.0)).abs() < 1e-6);
        assert!((out[1] - sig(-0.75)).abs() < 1e-6);
        assert!(Mlp::new("bad", spec.clone(), vec![l2.clone(), l1.clone()]).is_err());
        assert!(Mlp::new("bad", spec.clone(), vec![l1]).is_err());
        assert!(Mlp::new("bad", spec, vec![]).is_err());
        let none = FeatureSpec {
            radii: vec![],
            shifted: false,
        };
        assert!(Mlp::new("bad", none, vec![l2]).is_err());
    }

    #[test]
    fn layout_has_no_overlaps() {
        let l = FeatureLayout {
            ncam: 4,
            scales: 2,
            shifted: true,
        };
        let mut seen = vec![false; l.dim()];
        let mut mark = |i: usize| {
            assert!(!seen[i], "index {i} twice");
            seen[i] = true;
        };
        for s in 0..2 {
            for p in 0..l.pairs() {
                mark(l.zncc(s, p));
                mark(l.pair_complete(s, p));
            }
            for c in 0..4 {
                mark(l.texture(s, c));
                mark(l.camera_complete(s, c));
            }
        }
        for p in 0..l.pairs() {
            mark(l.center_difference(p));
            mark(l.shifted_zncc(p));
            mark(l.shifted_complete(p));
        }
        assert!(seen.iter().all(|&s| s));
        assert_eq!(l.dim(), 2 * 20 + 3 * 6);
        assert_eq!(camera_pairs(4).len(), 6);
    }
}
