//! A learnt pick after the network, at the output grid: where a depth edge lies, the
//! cascade's answer is often a blend of the two surfaces (a soft argmax over both), and the
//! right surface is usually one of the extremes of the answers around the pixel (
//! the nearest of a pixel's 5 x 5 minimum, maximum and own answer has a third less error).
//! The cameras' colours at those depths and the shape of the answer around say which one.
//!
//! [`PickRefiner`] reads, per output pixel ([`PickLayout`] says exactly which):
//!
//! - the answer `v` (index units of `N`), the coarse stage's spread, and the minimum `m` and
//!   maximum `M` of the answers around (wrapping in longitude) over one or more windows;
//! - at each of the depths `v`, `m`, `M`, every camera's gray value there (each image
//!   normalised by its own mean and standard deviation, bilinear, 0 where the camera does not
//!   see the point) and whether it sees it;
//! - optionally (pick-3), at each of those depths, the cameras' mean pairwise ZNCC
//!   over a small window of the output grid;
//!
//! and a small U-Net (3x3 convolutions wrapping in longitude, three stride-2 levels, bilinear
//! upsampling with skip concatenations, `width`, `2 width`, `3 width`, `4 width` channels)
//! scores the candidates: `v` and the minimum and maximum over windows around it (pick-1/2:
//! 3 x 3, 5 x 5 and 9 x 9). The answer is their softmax-weighted mean.
//!
//! It is trained outside the network, on the network's answers on frames it never trained on
//! (`scripts/pick/`, PyTorch; the weights are written as safetensors with the
//! module names of that script and the layout in their metadata), and runs on the host with
//! the convolution kernel of [`crate::hostconv`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use omnimvs_core::GrayImage;
use omnimvs_core::interp::{sample_inside_f64, upsample_half_pixel};
pub use omnimvs_core::safetensors::Tensors;
use omnimvs_data::edges::neighbour_min_max;
use omnimvs_stereo::camera_pairs;
use rayon::prelude::*;

use crate::error::NetError;
use crate::hostconv::{HostConv, Padding};
use crate::pixel::PixelSampler;
use crate::pixel::box_sum;

/// Which candidates a pick scores and which inputs it reads. A pick's safetensors carry it in
/// their metadata (`candidate_radii`, `depth_radii`, `zncc`: comma-separated integers, as
/// `scripts/pick/train_pick.py` writes them); a file without them has pick-1/2's
/// layout, [`PickLayout::default`].
///
/// Inputs, in order:
///
/// - `v / 192` and `spread / 30`, then for each of `depth_radii` with `m` and `M` the minimum
///   and maximum of the answers over the `(2 r + 1)^2` pixels around: `(M - m) / 32`,
///   `(m - v) / 32`, `(M - v) / 32`;
/// - at each sampled depth (`v`, then `m` and `M` of each of `depth_radii`), every camera's
///   normalised gray value there and whether it sees the point;
/// - with `zncc = k > 0`, per sampled depth: the mean over the pairs of cameras that count of
///   the ZNCC of their gray values over the `k x k` pixels of the output grid around (each
///   pixel at its own depth of that map; columns wrap, rows stop at the border; a pair counts
///   where both see the centre and both see at least half the window), and the fraction of
///   the pairs that count.
///
/// - with `coarse_modes = k > 0`, for each of the coarse stage's `k` most probable
///   modes ([`CoarseModes`]): `(mode - v) / 32`, its probability mass, and the mean pairwise
///   ZNCC and fraction of pairs that count (as above, over [`MODE_ZNCC`] x [`MODE_ZNCC`]) with
///   every camera sampled at the mode's depth; then the same ZNCC and fraction at `v`.
///
/// Candidates: `v`, then the minimum and maximum over each of `candidate_radii`, then the
/// `coarse_modes` modes' depths.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PickLayout {
    /// Radii of the candidates' neighbourhoods.
    pub candidate_radii: Vec<usize>,
    /// Radii whose minimum and maximum depths are sampled besides the answer.
    pub depth_radii: Vec<usize>,
    /// Side of the ZNCC window (odd), 0 for no ZNCC channels.
    pub zncc: usize,
    /// How many of the coarse stage's modes are candidates (0: none).
    pub coarse_modes: usize,
}

/// Side of the window of the ZNCC read at the coarse modes' depths and at the answer's
/// ([`PickLayout::coarse_modes`]).
pub const MODE_ZNCC: usize = 5;

/// Most coarse modes a layout may ask for.
pub const MAX_COARSE_MODES: usize = 8;

/// The coarse stage's most probable modes, on the output grid. Where the network
/// misses a whole region, its coarse distribution often still holds the right surface as
/// another mode: on things validation frames 481-490, the truth lay within 6 index units of
/// one of the three most probable modes at 37 % of the pixels the network missed by more than
/// 10 (`research/pick.md`).
///
/// A mode is a local maximum of a coarse pixel's distribution over its spheres (at least its
/// lower neighbour's probability, more than its upper's); its mass is the probability of the
/// sphere and its two neighbours, its depth their probability-weighted mean index. Modes are
/// ordered by mass (ties: the nearer sphere first); a pixel with fewer modes than asked for
/// repeats its first mode's depth with mass 0. Each output pixel takes the coarse pixel it
/// lies in (the grids share their extent).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoarseModes {
    /// Modes per pixel.
    pub count: usize,
    /// Their depths, `[count, h, w]`, index units of `N`.
    pub index: Vec<f32>,
    /// Their probability masses, `[count, h, w]`.
    pub mass: Vec<f32>,
}

impl CoarseModes {
    /// No modes (for a pick whose layout reads none).
    pub fn none() -> Self {
        Self::default()
    }

    /// The `count` most probable modes of the distribution `prob` over the spheres `hyp`
    /// (both `[k, h, w]` on the coarse grid; index units of `N`), on the output grid `[oh, ow]`.
    ///
    /// # Errors
    /// [`NetError::Shape`] when `prob` or `hyp` do not hold `[k, h, w]` values, or the output
    /// grid is empty.
    pub fn from_distribution(
        prob: &[f32],
        hyp: &[f32],
        [k, h, w]: [usize; 3],
        count: usize,
        [oh, ow]: [usize; 2],
    ) -> Result<Self, NetError> {
        let plane = h * w;
        if prob.len() != k * plane || hyp.len() != k * plane || k == 0 || oh * ow == 0 {
            return Err(NetError::Shape {
                what: "coarse modes: distribution and spheres [k, h, w] onto a grid".into(),
                expected: vec![k, h, w],
                actual: vec![prob.len(), hyp.len(), oh, ow],
            });
        }
        // Per coarse pixel, its modes' (index, mass).
        let coarse: Vec<Vec<(f32, f32)>> = (0..plane)
            .into_par_iter()
            .map(|p| {
                let at = |i: usize| prob[i * plane + p];
                let mut modes: Vec<(usize, f32, f32)> = Vec::new();
                for i in 0..k {
                    let lower = if i > 0 { at(i - 1) } else { f32::NEG_INFINITY };
                    let upper = if i + 1 < k {
                        at(i + 1)
                    } else {
                        f32::NEG_INFINITY
                    };
                    if at(i) >= lower && at(i) > upper {
                        let (mut mass, mut sum) = (0f32, 0f32);
                        for j in i.saturating_sub(1)..(i + 2).min(k) {
                            mass += at(j);
                            sum += at(j) * hyp[j * plane + p];
                        }
                        let index = if mass > 0.0 {
                            sum / mass
                        } else {
                            hyp[i * plane + p]
                        };
                        modes.push((i, mass, index));
                    }
                }
                modes.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                let first = modes.first().map_or(hyp[p], |m| m.2);
                (0..count)
                    .map(|j| modes.get(j).map_or((first, 0.0), |m| (m.2, m.1)))
                    .collect()
            })
            .collect();
        let out_plane = oh * ow;
        let mut index = vec![0f32; count * out_plane];
        let mut mass = vec![0f32; count * out_plane];
        for r in 0..oh {
            let cr = ((2 * r + 1) * h / (2 * oh)).min(h - 1);
            for c in 0..ow {
                let cc = ((2 * c + 1) * w / (2 * ow)).min(w - 1);
                for (j, &(i, m)) in coarse[cr * w + cc].iter().enumerate() {
                    index[j * out_plane + r * ow + c] = i;
                    mass[j * out_plane + r * ow + c] = m;
                }
            }
        }
        Ok(Self { count, index, mass })
    }
}

impl Default for PickLayout {
    /// pick-1 and pick-2's: candidates over 3 x 3, 5 x 5, 9 x 9; depths at the 5 x 5
    /// extremes; no ZNCC.
    fn default() -> Self {
        Self {
            candidate_radii: vec![1, 2, 4],
            depth_radii: vec![2],
            zncc: 0,
            coarse_modes: 0,
        }
    }
}

impl PickLayout {
    /// The layout in a safetensors' metadata (pick-1/2's where it has none of the keys).
    ///
    /// # Errors
    /// A message naming the key whose value is not a list of integers in range.
    pub fn from_metadata(metadata: &HashMap<String, String>) -> Result<Self, String> {
        let mut layout = Self::default();
        let list = |key: &str| -> Result<Option<Vec<usize>>, String> {
            metadata
                .get(key)
                .map(|text| {
                    text.split(',')
                        .map(|t| t.trim().parse::<usize>())
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|_| {
                            format!(
                                "metadata `{key}` reads {text:?}: expected comma-separated integers"
                            )
                        })
                })
                .transpose()
        };
        if let Some(radii) = list("candidate_radii")? {
            layout.candidate_radii = radii;
        }
        if let Some(radii) = list("depth_radii")? {
            layout.depth_radii = radii;
        }
        if let Some(k) = list("zncc")? {
            layout.zncc = match k[..] {
                [k] if k == 0 || (!k.is_multiple_of(2) && k <= 31) => k,
                _ => {
                    return Err(format!(
                        "metadata `zncc` reads {k:?}: expected 0 or an odd window side up to 31"
                    ));
                }
            };
        }
        if let Some(k) = list("coarse_modes")? {
            layout.coarse_modes = match k[..] {
                [k] if k <= MAX_COARSE_MODES => k,
                _ => {
                    return Err(format!(
                        "metadata `coarse_modes` reads {k:?}: expected one count up to {MAX_COARSE_MODES}"
                    ));
                }
            };
        }
        let in_range = |radii: &[usize]| radii.iter().all(|&r| (1..=64).contains(&r));
        if layout.candidate_radii.is_empty() || !in_range(&layout.candidate_radii) {
            return Err(format!(
                "metadata `candidate_radii` reads {:?}: expected radii from 1 to 64",
                layout.candidate_radii
            ));
        }
        if !in_range(&layout.depth_radii) {
            return Err(format!(
                "metadata `depth_radii` reads {:?}: expected radii from 1 to 64",
                layout.depth_radii
            ));
        }
        Ok(layout)
    }

    /// Number of candidates scored.
    pub fn candidates(&self) -> usize {
        1 + 2 * self.candidate_radii.len() + self.coarse_modes
    }

    /// Number of depths sampled per pixel.
    pub fn depths(&self) -> usize {
        1 + 2 * self.depth_radii.len()
    }

    /// Channels of the answer's neighbourhood (before the cameras').
    pub fn answer_channels(&self) -> usize {
        2 + 3 * self.depth_radii.len()
    }

    /// Input channels for a rig of `cameras`.
    pub fn input_channels(&self, cameras: usize) -> usize {
        self.answer_channels()
            + 2 * cameras * self.depths()
            + self.zncc_channels()
            + self.mode_channels()
    }

    /// Channels of the ZNCC at the sampled depths.
    fn zncc_channels(&self) -> usize {
        if self.zncc > 0 { 2 * self.depths() } else { 0 }
    }

    /// Channels of the coarse modes (after every other).
    pub fn mode_channels(&self) -> usize {
        if self.coarse_modes > 0 {
            4 * self.coarse_modes + 2
        } else {
            0
        }
    }

    /// The cameras a first layer of `inputs` channels was trained for, if any.
    pub fn cameras_for(&self, inputs: usize) -> Option<usize> {
        let fixed = self.input_channels(0);
        let per_camera = 2 * self.depths();
        (inputs > fixed && (inputs - fixed).is_multiple_of(per_camera))
            .then(|| (inputs - fixed) / per_camera)
    }

    /// The candidates `[candidates(), h, w]`: the answer, then the minimum and maximum over
    /// each of `candidate_radii` (wrapping in longitude), then the first `coarse_modes` of
    /// `modes` (which must hold that many on the grid).
    pub fn candidate_maps(&self, index: &[f32], modes: &CoarseModes, size: [usize; 2]) -> Vec<f32> {
        self.candidates_from(index, modes, &extremes(index, size, &self.candidate_radii))
    }

    /// [`Self::candidate_maps`] from the extremes of every radius it needs.
    fn candidates_from(&self, index: &[f32], modes: &CoarseModes, extremes: &Extremes) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.candidates() * index.len());
        out.extend_from_slice(index);
        for radius in &self.candidate_radii {
            let (low, high) = &extremes[radius];
            out.extend_from_slice(low);
            out.extend_from_slice(high);
        }
        out.extend_from_slice(&modes.index[..self.coarse_modes * index.len()]);
        out
    }

    /// The answer: each pixel's candidates ([`Self::candidate_maps`] of `index` and `modes`)
    /// weighted by the softmax of their `logits` `[candidates(), h, w]`.
    pub fn combine(
        &self,
        logits: &[f32],
        index: &[f32],
        modes: &CoarseModes,
        size: [usize; 2],
    ) -> Vec<f32> {
        self.combine_candidates(logits, &self.candidate_maps(index, modes, size))
    }

    /// [`Self::combine`] of the candidate maps themselves.
    fn combine_candidates(&self, logits: &[f32], candidates: &[f32]) -> Vec<f32> {
        let count = self.candidates();
        let plane = candidates.len() / count;
        (0..plane)
            .into_par_iter()
            .with_min_len(1024)
            .map(|p| {
                let mut best = f32::NEG_INFINITY;
                for k in 0..count {
                    best = best.max(logits[k * plane + p]);
                }
                let (mut num, mut den) = (0f32, 0f32);
                for k in 0..count {
                    let e = (logits[k * plane + p] - best).exp();
                    num += e * candidates[k * plane + p];
                    den += e;
                }
                num / den
            })
            .collect()
    }

    /// The input channels `[input_channels(cameras), h, w]` (the type's docs) for the answer
    /// `index` and the coarse `spread` (index units of the sampler's hypotheses, on its grid)
    /// and `modes` (at least `coarse_modes` of them on the grid), from the frame's `images`
    /// (rig order, the cameras' own sizes).
    ///
    /// # Errors
    /// [`NetError::Shape`] for maps or images of other sizes, or too few modes.
    pub fn inputs(
        &self,
        index: &[f32],
        spread: &[f32],
        modes: &CoarseModes,
        sampler: &PixelSampler,
        images: &[GrayImage],
    ) -> Result<Vec<f32>, NetError> {
        let size = check_sizes(index, spread, sampler, images)?;
        self.check_modes(modes, size)?;
        let extremes = extremes(index, size, &self.depth_radii);
        Ok(self.inputs_from(
            index,
            spread,
            modes,
            sampler,
            &Frame::new(images),
            &extremes,
        ))
    }

    /// Refuses `modes` with fewer than `coarse_modes` modes on the grid `[h, w]`.
    fn check_modes(&self, modes: &CoarseModes, [h, w]: [usize; 2]) -> Result<(), NetError> {
        let plane = h * w;
        if self.coarse_modes > 0
            && (modes.count < self.coarse_modes
                || modes.index.len() != modes.count * plane
                || modes.mass.len() != modes.count * plane)
        {
            return Err(NetError::Shape {
                what: "pick: coarse modes on the grid".into(),
                expected: vec![self.coarse_modes, h, w],
                actual: vec![modes.count, modes.index.len(), modes.mass.len()],
            });
        }
        Ok(())
    }

    /// [`Self::inputs`] of maps and images of the right sizes, from the extremes of every radius
    /// it needs.
    fn inputs_from(
        &self,
        index: &[f32],
        spread: &[f32],
        modes: &CoarseModes,
        sampler: &PixelSampler,
        frame: &Frame,
        extremes: &Extremes,
    ) -> Vec<f32> {
        let (images, normalised) = (frame.images, &frame.normalised);
        let (h, w) = (sampler.grid().height, sampler.grid().width);
        let plane = h * w;
        let cameras = images.len();
        let mut out = vec![0f32; self.input_channels(cameras) * plane];
        out[..plane]
            .iter_mut()
            .zip(index)
            .for_each(|(o, &v)| *o = v / 192.0);
        out[plane..2 * plane]
            .iter_mut()
            .zip(spread)
            .for_each(|(o, &s)| *o = s / 30.0);
        let mut depths: Vec<&[f32]> = vec![index];
        for (i, radius) in self.depth_radii.iter().enumerate() {
            let (low, high) = &extremes[radius];
            let channel = 2 + 3 * i;
            for p in 0..plane {
                let (v, m, big_m) = (index[p], low[p], high[p]);
                out[channel * plane + p] = (big_m - m) / 32.0;
                out[(channel + 1) * plane + p] = (m - v) / 32.0;
                out[(channel + 2) * plane + p] = (big_m - v) / 32.0;
            }
            depths.push(low);
            depths.push(high);
        }
        let first = self.answer_channels();
        for (d, map) in depths.iter().enumerate() {
            let channel = first + 2 * d * cameras;
            sample_cameras(
                map,
                sampler,
                images,
                normalised,
                &mut out[channel * plane..(channel + 2 * cameras) * plane],
            );
        }
        let zncc_first = first + 2 * cameras * depths.len();
        if self.coarse_modes > 0 {
            let mode_first = zncc_first + self.zncc_channels();
            let (head, tail) = out.split_at_mut(mode_first * plane);
            let mut samples = vec![0f32; 2 * cameras * plane];
            for (j, block) in tail
                .chunks_mut(4 * plane)
                .take(self.coarse_modes)
                .enumerate()
            {
                let mode = &modes.index[j * plane..(j + 1) * plane];
                let (offset, rest) = block.split_at_mut(plane);
                let (mass, pair) = rest.split_at_mut(plane);
                offset
                    .iter_mut()
                    .zip(mode.iter().zip(index))
                    .for_each(|(o, (&m, &v))| *o = (m - v) / 32.0);
                mass.copy_from_slice(&modes.mass[j * plane..(j + 1) * plane]);
                sample_cameras(mode, sampler, images, normalised, &mut samples);
                let (mean, fraction) = pair.split_at_mut(plane);
                zncc_of_cameras(&samples, cameras, [h, w], MODE_ZNCC, mean, fraction);
            }
            // The ZNCC at the answer, from its samples above.
            let at_answer = &head[first * plane..(first + 2 * cameras) * plane];
            let (mean, fraction) = tail[4 * self.coarse_modes * plane..].split_at_mut(plane);
            zncc_of_cameras(at_answer, cameras, [h, w], MODE_ZNCC, mean, fraction);
        }
        if self.zncc > 0 {
            let (head, tail) = out.split_at_mut(zncc_first * plane);
            let head = &head[first * plane..];
            tail[..self.zncc_channels() * plane]
                .par_chunks_mut(2 * plane)
                .enumerate()
                .for_each(|(d, pair)| {
                    let channels = &head[2 * d * cameras * plane..2 * (d + 1) * cameras * plane];
                    let (mean, fraction) = pair.split_at_mut(plane);
                    zncc_of_cameras(channels, cameras, [h, w], self.zncc, mean, fraction);
                });
        }
        out
    }
}

/// Every camera's normalised gray value (`normalised`: each image's mean and standard deviation)
/// and whether it sees the point at each pixel's depth `map` (index units of the sampler's
/// hypotheses), into `out` `[cameras x (gray, sees), h, w]` (both 0 where a camera does not see
/// the point).
fn sample_cameras(
    map: &[f32],
    sampler: &PixelSampler,
    images: &[GrayImage],
    normalised: &[(f64, f64)],
    out: &mut [f32],
) {
    let w = sampler.grid().width;
    let plane = map.len();
    let hypotheses = sampler.hypotheses();
    // The depth's inverse depth per pixel, once for every camera.
    let inv: Vec<f32> = map
        .iter()
        .map(|&n| hypotheses.inv_depth(f64::from(n)).max(1e-6) as f32)
        .collect();
    for (c, (image, &(mean, std))) in images.iter().zip(normalised).enumerate() {
        let (gray, sees) = out[2 * c * plane..2 * (c + 1) * plane].split_at_mut(plane);
        gray.par_chunks_mut(w)
            .zip(sees.par_chunks_mut(w))
            .enumerate()
            .for_each(|(row, (gray, sees))| {
                for col in 0..w {
                    let p = row * w + col;
                    if let Some((x, y)) = sampler.project(c, p, inv[p])
                        && let Some(value) = sample_inside_f64(image, f64::from(x), f64::from(y))
                    {
                        gray[col] = ((value - mean) / (std + 1e-9)) as f32;
                        sees[col] = 1.0;
                    } else {
                        gray[col] = 0.0;
                        sees[col] = 0.0;
                    }
                }
            });
    }
}

/// The minimum and maximum of the answers around each pixel, by radius (wrapping in longitude).
type Extremes = HashMap<usize, (Vec<f32>, Vec<f32>)>;

/// [`Extremes`] of `index` for each of `radii`, each radius once.
fn extremes(index: &[f32], size: [usize; 2], radii: &[usize]) -> Extremes {
    let mut out = Extremes::new();
    for &radius in radii {
        out.entry(radius)
            .or_insert_with(|| neighbour_min_max(index, size, true, radius));
    }
    out
}

/// The grid's `[h, w]` when `index` and `spread` cover the sampler's grid and `images` are one
/// per camera of the camera's size.
fn check_sizes(
    index: &[f32],
    spread: &[f32],
    sampler: &PixelSampler,
    images: &[GrayImage],
) -> Result<[usize; 2], NetError> {
    let (h, w) = (sampler.grid().height, sampler.grid().width);
    let plane = h * w;
    if index.len() != plane || spread.len() != plane {
        return Err(NetError::Shape {
            what: "pick: index and spread maps".into(),
            expected: vec![h, w],
            actual: vec![index.len(), spread.len()],
        });
    }
    let cameras = sampler.num_cameras();
    if images.len() != cameras {
        return Err(NetError::Shape {
            what: "pick: an image per camera of the rig".into(),
            expected: vec![cameras],
            actual: vec![images.len()],
        });
    }
    for (camera, image) in images.iter().enumerate() {
        let (width, height) = sampler.image_size(camera);
        let size = [height as usize, width as usize];
        if size != [image.height, image.width] {
            return Err(NetError::Shape {
                what: "pick: an image of its camera's size".into(),
                expected: size.to_vec(),
                actual: vec![image.height, image.width],
            });
        }
    }
    Ok([h, w])
}

/// Mean ZNCC over the camera pairs that count and the fraction that count ([`PickLayout`]'s
/// docs), from `channels` `[cameras x (gray, sees), h, w]`, into `mean` and `fraction`.
fn zncc_of_cameras(
    channels: &[f32],
    cameras: usize,
    [h, w]: [usize; 2],
    k: usize,
    mean: &mut [f32],
    fraction: &mut [f32],
) {
    let plane = h * w;
    let pairs = camera_pairs(cameras);
    let window = (k * k) as f64;
    // Per pair: the sum of ZNCC where it counts, and where it counts.
    let per_pair: Vec<(Vec<f64>, Vec<f64>)> = pairs
        .par_iter()
        .map(|&(i, j)| {
            let at = |c: usize, which: usize| {
                &channels[(2 * c + which) * plane..(2 * c + which + 1) * plane]
            };
            let (a, b, sa_, sb_) = (at(i, 0), at(j, 0), at(i, 1), at(j, 1));
            // n, Σa, Σb, Σa², Σb², Σab over the pixels both see.
            let mut sums: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0f64; plane]);
            for p in 0..plane {
                let m = f64::from(sa_[p] * sb_[p]);
                let (x, y) = (f64::from(a[p]), f64::from(b[p]));
                sums[0][p] = m;
                sums[1][p] = m * x;
                sums[2][p] = m * y;
                sums[3][p] = m * x * x;
                sums[4][p] = m * y * y;
                sums[5][p] = m * x * y;
            }
            let [n, sa, sb, saa, sbb, sab] = sums.map(|sum| box_sum(&sum, h, w, k / 2));
            let mut z_sum = vec![0f64; plane];
            let mut counted = vec![0f64; plane];
            for p in 0..plane {
                if sa_[p] * sb_[p] > 0.0 && 2.0 * n[p] >= window {
                    let nn = n[p].max(1.0);
                    let cov = sab[p] - sa[p] * sb[p] / nn;
                    let va = (saa[p] - sa[p] * sa[p] / nn).max(0.0);
                    let vb = (sbb[p] - sb[p] * sb[p] / nn).max(0.0);
                    z_sum[p] = cov / (va * vb + (0.01 * n[p]).powi(2) + 1e-12).sqrt();
                    counted[p] = 1.0;
                }
            }
            (z_sum, counted)
        })
        .collect();
    let total = pairs.len().max(1) as f64;
    mean.par_iter_mut()
        .zip(fraction.par_iter_mut())
        .enumerate()
        .for_each(|(p, (mean, fraction))| {
            let (sum, count) = per_pair
                .iter()
                .fold((0f64, 0f64), |(s, c), (z, n)| (s + z[p], c + n[p]));
            *mean = if count > 0.0 {
                (sum / count) as f32
            } else {
                0.0
            };
            *fraction = (count / total) as f32;
        });
}

/// The bundled pick, trained on the bundled cascade's answers (`models/omnimvs-cascade-pick.safetensors`).
pub const BUNDLED_PICK: &[u8] = include_bytes!("../../../models/omnimvs-cascade-pick.safetensors");

/// Its label in errors and reports.
pub const BUNDLED_PICK_LABEL: &str = "models/omnimvs-cascade-pick.safetensors";

/// The bundled second pick, run after [`BUNDLED_PICK`] and trained on its answers (
/// `models/omnimvs-cascade-pick2.safetensors`).
pub const BUNDLED_SECOND_PICK: &[u8] =
    include_bytes!("../../../models/omnimvs-cascade-pick2.safetensors");

/// Its label in errors and reports.
pub const BUNDLED_SECOND_PICK_LABEL: &str = "models/omnimvs-cascade-pick2.safetensors";

/// One 3x3 convolution of the U-Net with its ReLU.
#[derive(Clone, Debug)]
struct Layer {
    conv: HostConv,
    relu: bool,
}

impl Layer {
    fn run(
        &self,
        input: &[f32],
        [c, h, w]: [usize; 3],
    ) -> Result<(Vec<f32>, [usize; 3]), NetError> {
        let (out, [oh, ow]) = self.conv.forward(input, [1, c, h, w], None, self.relu)?;
        Ok((out, [self.conv.out_channels(), oh, ow]))
    }
}

/// The learnt pick (module docs).
#[derive(Clone, Debug)]
pub struct PickRefiner {
    cameras: usize,
    layout: PickLayout,
    /// Encoder levels, two layers each (the first of levels 1-3 at stride 2).
    encoder: [[Layer; 2]; 4],
    /// Decoder layers from the coarsest: `d2`, `d1`, `d0`.
    decoder: [Layer; 3],
    head: Layer,
    /// The pick run after this one on its answer, if any.
    then: Option<Box<PickRefiner>>,
}

/// A safetensors file's tensors (`F32` only); `path` labels errors.
///
/// # Errors
/// [`NetError::Weights`] for a file that is not safetensors or holds another dtype.
pub fn read_safetensors(bytes: &[u8], path: &Path) -> Result<Tensors, NetError> {
    read_safetensors_with_metadata(bytes, path).map(|(tensors, _)| tensors)
}

/// [`read_safetensors`], with the header's `__metadata__` (empty without one).
///
/// # Errors
/// As [`read_safetensors`].
pub fn read_safetensors_with_metadata(
    bytes: &[u8],
    path: &Path,
) -> Result<(Tensors, HashMap<String, String>), NetError> {
    omnimvs_core::safetensors::read_safetensors(bytes, path).map_err(|e| NetError::Weights {
        path: e.path,
        message: e.message,
    })
}

impl PickRefiner {
    /// The bundled pick (trained on the bundled cascade's answers, four cameras).
    ///
    /// # Errors
    /// [`NetError::Weights`] if the compiled-in file does not match (a build defect).
    pub fn bundled() -> Result<Self, NetError> {
        Self::from_bytes(BUNDLED_PICK, Path::new(BUNDLED_PICK_LABEL))
    }

    /// The bundled pick followed by the bundled second pick, trained on its answers (
    /// more accurate, and a pick's time slower; `--pick chain`).
    ///
    /// # Errors
    /// [`NetError::Weights`] if the compiled-in files do not match (a build defect).
    pub fn bundled_chain() -> Result<Self, NetError> {
        Self::bundled()?.followed_by(Self::from_bytes(
            BUNDLED_SECOND_PICK,
            Path::new(BUNDLED_SECOND_PICK_LABEL),
        )?)
    }

    /// This pick with `next` run after it on its answer (after the last of its chain).
    ///
    /// # Errors
    /// [`NetError::Shape`] when `next` was made for another number of cameras.
    pub fn followed_by(mut self, next: Self) -> Result<Self, NetError> {
        if next.cameras != self.cameras {
            return Err(NetError::Shape {
                what: "pick: cameras of the pick run after another".into(),
                expected: vec![self.cameras],
                actual: vec![next.cameras],
            });
        }
        self.then = Some(Box::new(match self.then.take() {
            Some(then) => then.followed_by(next)?,
            None => next,
        }));
        Ok(self)
    }

    /// How many picks run, this one and those after it.
    pub fn passes(&self) -> usize {
        1 + self.then.as_ref().map_or(0, |then| then.passes())
    }

    /// The most coarse modes any pick of the chain reads ([`PickLayout::coarse_modes`]).
    pub fn coarse_modes(&self) -> usize {
        let after = self.then.as_ref().map_or(0, |then| then.coarse_modes());
        self.layout.coarse_modes.max(after)
    }

    /// Reads a pick from a safetensors file.
    ///
    /// # Errors
    /// [`NetError::Io`] when the file cannot be read, [`NetError::Weights`] when it is not a
    /// pick's weights.
    pub fn load(path: &Path) -> Result<Self, NetError> {
        let bytes = std::fs::read(path).map_err(|source| NetError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes, path)
    }

    /// A pick from safetensors bytes; `path` labels errors. The sizes (cameras, width) are
    /// read from the tensors.
    ///
    /// # Errors
    /// [`NetError::Weights`] for a tensor missing, of another size, or a file that is not
    /// safetensors.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, NetError> {
        let (mut tensors, metadata) = read_safetensors_with_metadata(bytes, path)?;
        let bad = |message: String| NetError::Weights {
            path: PathBuf::from(path),
            message,
        };
        let layout = PickLayout::from_metadata(&metadata).map_err(bad)?;
        let inputs = tensors
            .get("e0.0.0.weight")
            .map(|(shape, _)| shape.get(1).copied().unwrap_or(0))
            .ok_or_else(|| bad("no tensor `e0.0.0.weight`: not a pick's weights".into()))?;
        let cameras = layout.cameras_for(inputs).ok_or_else(|| {
            bad(format!(
                "`e0.0.0.weight` reads {inputs} channels: expected {} + {} per camera for the layout {layout:?}",
                layout.input_channels(0),
                2 * layout.depths()
            ))
        })?;
        let width = tensors["e0.0.0.weight"].0[0];
        let mut layer = |name: &str, c_in: usize, c_out: usize, stride: usize, relu: bool| {
            let (wshape, weight) = tensors
                .remove(&format!("{name}.weight"))
                .ok_or_else(|| bad(format!("no tensor `{name}.weight`")))?;
            let (bshape, bias) = tensors
                .remove(&format!("{name}.bias"))
                .ok_or_else(|| bad(format!("no tensor `{name}.bias`")))?;
            if wshape != [c_out, c_in, 3, 3] || bshape != [c_out] {
                return Err(bad(format!(
                    "`{name}`: weight {wshape:?} and bias {bshape:?}, expected [{c_out}, {c_in}, 3, 3] and [{c_out}]"
                )));
            }
            let conv = HostConv::new(
                [c_in, c_out],
                [3, 3],
                [stride, stride],
                [1, 1],
                Padding {
                    rows: 1,
                    cols: 1,
                    wrap_cols: true,
                },
                weight,
                bias,
            )?;
            Ok(Layer { conv, relu })
        };
        let w = width;
        let encoder = [
            [
                layer("e0.0.0", inputs, w, 1, true)?,
                layer("e0.1.0", w, w, 1, true)?,
            ],
            [
                layer("e1.0.0", w, 2 * w, 2, true)?,
                layer("e1.1.0", 2 * w, 2 * w, 1, true)?,
            ],
            [
                layer("e2.0.0", 2 * w, 3 * w, 2, true)?,
                layer("e2.1.0", 3 * w, 3 * w, 1, true)?,
            ],
            [
                layer("e3.0.0", 3 * w, 4 * w, 2, true)?,
                layer("e3.1.0", 4 * w, 4 * w, 1, true)?,
            ],
        ];
        let decoder = [
            layer("d2.0", 7 * w, 3 * w, 1, true)?,
            layer("d1.0", 5 * w, 2 * w, 1, true)?,
            layer("d0.0", 3 * w, w, 1, true)?,
        ];
        let head = layer("head", w, layout.candidates(), 1, false)?;
        if let Some(name) = tensors.keys().next() {
            return Err(bad(format!("tensor `{name}` is not a pick's")));
        }
        Ok(Self {
            cameras,
            layout,
            encoder,
            decoder,
            head,
            then: None,
        })
    }

    /// Cameras it was trained for.
    pub fn cameras(&self) -> usize {
        self.cameras
    }

    /// Its candidates and inputs (this pick's, not those of the picks after it).
    pub fn layout(&self) -> &PickLayout {
        &self.layout
    }

    /// The picked answer for `index` (index units of the sampler's hypotheses, row-major on
    /// its grid: the cascade's full-resolution [`PixelSampler`], which projects the output
    /// grid into the rig's cameras), with the coarse `spread` on the same grid, from the
    /// frame's `images` (rig order, the cameras' own sizes).
    ///
    /// # Errors
    /// [`NetError::Shape`] for maps of other sizes, or another number of cameras.
    pub fn refine(
        &self,
        index: &[f32],
        spread: &[f32],
        modes: &CoarseModes,
        sampler: &PixelSampler,
        images: &[GrayImage],
    ) -> Result<Vec<f32>, NetError> {
        self.refine_frame(index, spread, modes, sampler, &Frame::new(images))
    }

    /// [`Self::refine`] with the frame's images normalised once for every pick of the chain.
    fn refine_frame(
        &self,
        index: &[f32],
        spread: &[f32],
        modes: &CoarseModes,
        sampler: &PixelSampler,
        frame: &Frame,
    ) -> Result<Vec<f32>, NetError> {
        let size = self.check(index, spread, sampler, frame.images)?;
        self.layout.check_modes(modes, size)?;
        // Each radius's extremes once, for the inputs and the candidates alike.
        let layout = &self.layout;
        let radii: Vec<usize> = layout
            .candidate_radii
            .iter()
            .chain(&layout.depth_radii)
            .copied()
            .collect();
        let extremes = extremes(index, size, &radii);
        let inputs = layout.inputs_from(index, spread, modes, sampler, frame, &extremes);
        let logits = self.scores(&inputs, size)?;
        let answer =
            layout.combine_candidates(&logits, &layout.candidates_from(index, modes, &extremes));
        match &self.then {
            Some(then) => then.refine_frame(&answer, spread, modes, sampler, frame),
            None => Ok(answer),
        }
    }

    /// The grid's `[h, w]` when the rig has this pick's cameras and the maps and images fit
    /// (the errors of [`Self::inputs`]).
    fn check(
        &self,
        index: &[f32],
        spread: &[f32],
        sampler: &PixelSampler,
        images: &[GrayImage],
    ) -> Result<[usize; 2], NetError> {
        self.check_cameras(sampler, images)?;
        check_sizes(index, spread, sampler, images)
    }

    /// Refuses a rig or a frame with another number of cameras than this pick's.
    fn check_cameras(&self, sampler: &PixelSampler, images: &[GrayImage]) -> Result<(), NetError> {
        let cameras = sampler.num_cameras();
        if cameras != self.cameras || images.len() != self.cameras {
            return Err(NetError::Shape {
                what: "pick: cameras of the rig and images".into(),
                expected: vec![self.cameras],
                actual: vec![cameras, images.len()],
            });
        }
        Ok(())
    }

    /// The input channels `[channels, h, w]` ([`PickLayout::inputs`]).
    ///
    /// # Errors
    /// [`NetError::Shape`] for maps or images of other sizes, or another number of cameras.
    pub fn inputs(
        &self,
        index: &[f32],
        spread: &[f32],
        modes: &CoarseModes,
        sampler: &PixelSampler,
        images: &[GrayImage],
    ) -> Result<Vec<f32>, NetError> {
        self.check_cameras(sampler, images)?;
        self.layout.inputs(index, spread, modes, sampler, images)
    }

    /// The candidates' logits `[candidates, h, w]` for `inputs` `[channels, h, w]`.
    ///
    /// # Errors
    /// [`NetError::Shape`] for inputs of another size.
    pub fn scores(&self, inputs: &[f32], [h, w]: [usize; 2]) -> Result<Vec<f32>, NetError> {
        let [first, second] = &self.encoder[0];
        let x = first.run(inputs, [self.layout.input_channels(self.cameras), h, w])?;
        let mut x = second.run(&x.0, x.1)?;
        // The output of every level but the coarsest, for the decoder's skips.
        let mut skips: Vec<(Vec<f32>, [usize; 3])> = Vec::with_capacity(3);
        for level in &self.encoder[1..] {
            let out = level[0].run(&x.0, x.1)?;
            skips.push(std::mem::replace(&mut x, out));
            x = level[1].run(&x.0, x.1)?;
        }
        for (layer, skip) in self.decoder.iter().zip(skips.iter().rev()) {
            let mut joined = upsample_half_pixel(&x.0, x.1, [skip.1[1], skip.1[2]]);
            joined.extend_from_slice(&skip.0);
            x = layer.run(&joined, [x.1[0] + skip.1[0], skip.1[1], skip.1[2]])?;
        }
        Ok(self.head.run(&x.0, x.1)?.0)
    }
}

/// A frame's images (rig order) with each one's mean and standard deviation, which the
/// cameras' samples are normalised by: computed once for every pick of a chain.
struct Frame<'a> {
    images: &'a [GrayImage],
    normalised: Vec<(f64, f64)>,
}

impl<'a> Frame<'a> {
    /// The images in parallel (two passes over 0.6 megapixels each).
    fn new(images: &'a [GrayImage]) -> Self {
        Self {
            images,
            normalised: images.par_iter().map(mean_and_std).collect(),
        }
    }
}

/// Mean and (population) standard deviation of an image's values.
fn mean_and_std(image: &GrayImage) -> (f64, f64) {
    let n = image.data.len().max(1) as f64;
    let mean = image.data.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let var = image
        .data
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n;
    (mean, var.sqrt())
}
