//! A stage's group-wise correlation on the host, for inference on a CPU.
//!
//! The tensor version ([`super::CascadeNet::correlation`]) gathers every camera's features at
//! every tap as a whole tensor, weights it, sums, squares: a dozen passes over `[samples,
//! channels]` tensors allocated afresh, memory-bound on a CPU (the full-resolution stage has
//! 512 k samples of 4 cameras). Here each sample is finished in one visit: its four taps of
//! every camera are read from channels-last copies of the feature maps and reduced in
//! registers to the sums, the camera-pair products and the group means. Same formulas in the
//! same order (the tests compare the two), no gradient: training uses the tensor version.

use burn::tensor::{Device, Tensor, TensorData};
use rayon::prelude::*;

use super::geometry::HostTaps;
use crate::error::NetError;
use crate::tensor::with_values;

pub use crate::config::MAX_CHANNELS;

/// Group-wise correlation of one stage from every camera's features `[1, C, rows, cols]` and
/// the stage's host taps over `dims = [K, H, W]`: `[1, groups + 1, K, H, W]`, the mean
/// product over the camera pairs that see a sample by groups of channels, then the share of
/// cameras that see it (as [`super::CascadeNet::correlation`]).
///
/// # Errors
/// [`NetError::Shape`] when the features and the taps disagree in cameras, sizes or channels,
/// or `groups` does not divide the channels.
pub fn correlation(
    features: &[Tensor<4>],
    taps: &HostTaps,
    dims: [usize; 3],
    groups: usize,
    device: &Device,
) -> Result<Tensor<5>, NetError> {
    let [k, h, w] = dims;
    let samples = k * h * w;
    let shape_error = |what: &str, expected: Vec<usize>, actual: Vec<usize>| NetError::Shape {
        what: format!("{what} (host correlation of a cascade stage)"),
        expected,
        actual,
    };
    if features.is_empty() || features.len() != taps.cameras.len() {
        return Err(shape_error(
            "feature maps",
            vec![taps.cameras.len()],
            vec![features.len()],
        ));
    }
    if taps.pair_count.len() != samples
        || taps.visibility.len() != samples
        || taps.cameras.iter().any(|t| t.len() != samples)
    {
        return Err(shape_error(
            "taps",
            vec![samples],
            taps.cameras.iter().map(Vec::len).collect(),
        ));
    }
    let mut channels = 0;
    for feature in features {
        let [b, c, rows, cols] = feature.dims();
        if b != 1
            || c == 0
            || c > MAX_CHANNELS
            || (channels != 0 && c != channels)
            || [rows, cols] != taps.feature_size
        {
            let [rows_t, cols_t] = taps.feature_size;
            return Err(shape_error(
                "feature maps",
                vec![1, channels.max(1), rows_t, cols_t],
                vec![b, c, rows, cols],
            ));
        }
        channels = c;
    }
    // Channels-last tables, the cameras in parallel.
    let tables = features
        .par_iter()
        .map(|feature| with_values(feature.clone(), "features", |v| channels_last(v, channels)))
        .collect::<Result<Vec<_>, _>>()?;
    if groups == 0 || channels % groups != 0 {
        return Err(shape_error("groups", vec![channels], vec![groups]));
    }

    // [S, G]: one sample per chunk, in parallel; the usual channel counts get a kernel of
    // their own (fixed-size arrays the compiler keeps in vector registers), the same
    // operations in the same order as the general one.
    let mut grouped = vec![0f32; samples * groups];
    let kernel = Kernel {
        tables: &tables,
        taps,
        channels,
        groups,
    };
    match channels {
        8 => kernel.run::<8>(&mut grouped),
        16 => kernel.run::<16>(&mut grouped),
        _ => kernel.run::<MAX_CHANNELS>(&mut grouped),
    }
    // [G + 1, S]: the groups, then the visibility.
    let mut volume = vec![0f32; (groups + 1) * samples];
    let (planes, visibility) = volume.split_at_mut(groups * samples);
    planes
        .par_chunks_exact_mut(samples)
        .enumerate()
        .for_each(|(g, plane)| {
            for (v, row) in plane.iter_mut().zip(grouped.chunks_exact(groups)) {
                *v = row[g];
            }
        });
    visibility.copy_from_slice(&taps.visibility);
    Ok(Tensor::from_data(
        TensorData::new(volume, [1, groups + 1, k, h, w]),
        device,
    ))
}

/// The per-sample work of [`correlation`]: channels-last feature tables, one per camera, and
/// the stage's taps.
struct Kernel<'a> {
    tables: &'a [Vec<f32>],
    taps: &'a HostTaps,
    /// Channels of every table.
    channels: usize,
    groups: usize,
}

impl Kernel<'_> {
    /// Group means `[S, G]` into `grouped`: `N` the tables' channels, or [`MAX_CHANNELS`] for
    /// the general kernel (arrays of that size, of which the tables' channels are used).
    fn run<const N: usize>(&self, grouped: &mut [f32]) {
        // A constant for the specialised kernels, so that their loops have a known length.
        let channels = if N < MAX_CHANNELS { N } else { self.channels };
        let per_group = channels / self.groups;
        grouped
            .par_chunks_mut(self.groups)
            .enumerate()
            .for_each(|(s, out)| {
                let mut sum = [0f32; N];
                let mut sum_sq = [0f32; N];
                let mut first = true;
                for (table, cam) in self.tables.iter().zip(&self.taps.cameras) {
                    let tap = &cam[s];
                    let mut warped = [0f32; N];
                    for (j, (&index, &weight)) in tap.index.iter().zip(&tap.weight).enumerate() {
                        let row = &table[index as usize * channels..][..channels];
                        for (v, &f) in warped[..channels].iter_mut().zip(row) {
                            // The tensor version: the first tap's product, then each next added.
                            *v = if j == 0 { f * weight } else { *v + f * weight };
                        }
                    }
                    for ((a, q), &v) in sum.iter_mut().zip(&mut sum_sq).zip(&warped[..channels]) {
                        if first {
                            (*a, *q) = (v, v * v);
                        } else {
                            *a += v;
                            *q += v * v;
                        }
                    }
                    first = false;
                }
                let pairs = self.taps.pair_count[s].max(1e-3);
                for (g, o) in out.iter_mut().enumerate() {
                    let range = g * per_group..(g + 1) * per_group;
                    let total: f32 = sum[range.clone()]
                        .iter()
                        .zip(&sum_sq[range])
                        .map(|(a, q)| (a * a - q) / 2.0)
                        .sum();
                    *o = total / per_group as f32 / pairs;
                }
            });
    }
}

/// `[C, P]` (channels first) to `[P, C]`.
fn channels_last(data: &[f32], channels: usize) -> Vec<f32> {
    let pixels = data.len() / channels;
    let mut out = vec![0f32; data.len()];
    for (c, plane) in data.chunks_exact(pixels).enumerate() {
        for (p, &v) in plane.iter().enumerate() {
            out[p * channels + c] = v;
        }
    }
    out
}
