//! burn-flex's 3x3 panorama convolution (`PanoConv2d`: columns padded circularly, rows with
//! zeros) against a direct host convolution (no im2col: each output row accumulated from three
//! padded input rows per input channel, four output channels at a time, rayon over rows and
//! channel blocks), on the cascade's refinement-stage layer shapes: the measurement behind
//! "Where the CPU time goes now" in the crate's README. Best of 7 rounds each, the same inputs
//! and weights; prints both times and the largest difference of their outputs.
//!
//!     cargo run --release -p omnimvs-net --example pano_conv_bench
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]

use std::time::Instant;

use burn::tensor::{Device, Distribution, Tensor};
use omnimvs_net::cascade::model::PanoConv2d;
use omnimvs_net::tensor::read_values;
use rayon::prelude::*;

/// Direct 3x3 convolution, stride 1, rows zero-padded, columns circular. `x` is `[ci, h, w]`,
/// `weight` `[co, ci, 3, 3]`; returns `[co, h, w]`.
fn direct(x: &[f32], ci: usize, h: usize, w: usize, weight: &[f32], bias: &[f32]) -> Vec<f32> {
    let co = bias.len();
    let wp = w + 2;
    let plane = (h + 2) * wp;
    let mut xp = vec![0.0f32; ci * plane];
    xp.par_chunks_mut(plane).enumerate().for_each(|(c, p)| {
        for r in 0..h {
            let src = &x[(c * h + r) * w..(c * h + r + 1) * w];
            let dst = &mut p[(r + 1) * wp..(r + 2) * wp];
            dst[0] = src[w - 1];
            dst[1..=w].copy_from_slice(src);
            dst[w + 1] = src[0];
        }
    });
    const BLOCK: usize = 4;
    let mut out = vec![0.0f32; co * h * w];
    // Parallel over (output-channel block, row).
    let blocks = co.div_ceil(BLOCK);
    let mut rows: Vec<(usize, usize, Vec<f32>)> = (0..blocks)
        .flat_map(|b| (0..h).map(move |r| (b, r, Vec::new())))
        .collect();
    rows.par_iter_mut().for_each(|(b, r, acc)| {
        let c0 = *b * BLOCK;
        let n = BLOCK.min(co - c0);
        acc.resize(n * w, 0.0);
        for k in 0..n {
            acc[k * w..(k + 1) * w].fill(bias[c0 + k]);
        }
        for c in 0..ci {
            for kh in 0..3 {
                let row = &xp[c * plane + (*r + kh) * wp..c * plane + (*r + kh) * wp + wp];
                for k in 0..n {
                    let wk = &weight[((c0 + k) * ci + c) * 9 + kh * 3..][..3];
                    let (a, bb, cc) = (wk[0], wk[1], wk[2]);
                    let o = &mut acc[k * w..(k + 1) * w];
                    for ((o, x0), (x1, x2)) in o
                        .iter_mut()
                        .zip(&row[..w])
                        .zip(row[1..=w].iter().zip(&row[2..w + 2]))
                    {
                        *o += a * x0 + bb * x1 + cc * x2;
                    }
                }
            }
        }
    });
    for (b, r, acc) in rows {
        let c0 = b * BLOCK;
        for k in 0..acc.len() / w {
            out[((c0 + k) * h + r) * w..((c0 + k) * h + r + 1) * w]
                .copy_from_slice(&acc[k * w..(k + 1) * w]);
        }
    }
    out
}

fn main() {
    let device = Device::default();
    for &(ci, co, h, w) in &[
        (46usize, 16usize, 160usize, 640usize),
        (16, 16, 160, 640),
        (54, 16, 160, 640),
        (42, 32, 80, 320),
        (32, 32, 80, 320),
    ] {
        // The network's own block: circular columns, zero rows, no batch norm or ReLU.
        let block = PanoConv2d::new([ci, co], 1, false, &device);
        let x = Tensor::<4>::random([1, ci, h, w], Distribution::Normal(0.0, 1.0), &device);
        let values = |t: Tensor<4>| read_values(t, "bench").unwrap();
        let weight = read_values(block.conv.weight.val(), "weight").unwrap();
        let bias = read_values(block.conv.bias.as_ref().unwrap().val(), "bias").unwrap();
        let xs = values(x.clone());
        let reference = values(block.forward(x.clone()));
        let mine = direct(&xs, ci, h, w, &weight, &bias);
        let max_diff = reference
            .iter()
            .zip(&mine)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        let time = |f: &dyn Fn()| {
            let mut best = f64::MAX;
            for _ in 0..7 {
                let t = Instant::now();
                f();
                best = best.min(t.elapsed().as_secs_f64());
            }
            best
        };
        let tb = time(&|| {
            let _ = block.forward(x.clone()).into_data();
        });
        let td = time(&|| {
            let y = direct(&values(x.clone()), ci, h, w, &weight, &bias);
            let _ =
                Tensor::<4>::from_data(burn::tensor::TensorData::new(y, [1, co, h, w]), &device);
        });
        println!(
            "{ci:3} -> {co:3} at {h}x{w}: burn {:.4} s, direct {:.4} s ({:.2}x), max diff {max_diff:.2e}",
            tb,
            td,
            tb / td
        );
    }
}
