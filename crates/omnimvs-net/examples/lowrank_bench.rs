//! The coarse regulariser's first convolution (3x3 over every sphere's channels) against the
//! same layer factorised into a 1x1 convolution to `k` channels and a 3x3 one from them, on
//! the bundled (40 x 160, 32 spheres) and the half-grid (80 x 320, 16 spheres) shapes. Best of 7
//! rounds each, random weights.
//!
//!     cargo run --release -p omnimvs-net --example lowrank_bench
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]

use std::time::Instant;

use burn::nn::PaddingConfig2d;
use burn::nn::conv::Conv2dConfig;
use burn::tensor::{Device, Distribution, Tensor};
use omnimvs_net::cascade::model::PanoConv2d;

fn main() {
    let device = Device::default();
    let time = |f: &dyn Fn()| {
        let mut best = f64::MAX;
        for _ in 0..7 {
            let t = Instant::now();
            f();
            best = best.min(t.elapsed().as_secs_f64());
        }
        best
    };
    for &(ci, co, h, w) in &[(352usize, 48usize, 40usize, 160usize), (240, 48, 80, 320)] {
        let x = Tensor::<4>::random([1, ci, h, w], Distribution::Normal(0.0, 1.0), &device);
        let full = PanoConv2d::new([ci, co], 1, false, &device);
        let tf = time(&|| {
            let _ = full.forward(x.clone()).into_data();
        });
        print!("{ci:3} -> {co} at {h}x{w}: 3x3 {tf:.4} s");
        for k in [32usize, 48, 64, 96] {
            let squeeze = Conv2dConfig::new([ci, k], [1, 1])
                .with_padding(PaddingConfig2d::Valid)
                .init(&device);
            let conv = PanoConv2d::new([k, co], 1, false, &device);
            let t = time(&|| {
                let _ = conv.forward(squeeze.forward(x.clone())).into_data();
            });
            print!(";  k {k}: {t:.4} s");
        }
        println!();
    }
}
