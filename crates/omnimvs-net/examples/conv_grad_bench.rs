//! Forward + backward of a small-channel 3x3 convolution on flex: burn's Conv2d (whose weight
//! gradient at batch 1 takes flex's direct small-channel path with the whole output map as
//! the kernel) against unfold + matmul (whose gradients are GEMMs).
#![allow(clippy::unwrap_used)]
use std::time::Instant;

use burn::module::Param;
use burn::nn::PaddingConfig2d;
use burn::nn::conv::Conv2dConfig;
use burn::tensor::module::unfold4d;
use burn::tensor::ops::UnfoldOptions;
use burn::tensor::{Device, Distribution, Tensor};

fn main() {
    let device = Device::flex().autodiff();
    for (cin, cout, h, w) in [
        (8, 8, 384, 400),
        (16, 16, 192, 200),
        (25, 16, 160, 640),
        (16, 5, 160, 640),
    ] {
        let x = Tensor::<4>::random([1, cin, h, w], Distribution::Default, &device).require_grad();
        let x5 = Tensor::<4>::random([5, cin, h, w], Distribution::Default, &device).require_grad();
        let conv = Conv2dConfig::new([cin, cout], [3, 3])
            .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
            .init(&device);
        let weight = Param::from_tensor(Tensor::<2>::random(
            [cout, cin * 9],
            Distribution::Default,
            &device,
        ));
        for _ in 0..2 {
            let t = Instant::now();
            let y = conv.forward(x.clone());
            let loss = y.sum();
            let _grads = loss.backward();
            let a = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let padded = x
                .clone()
                .pad([(1, 1), (1, 1)], burn::tensor::ops::PadMode::Constant(0.0));
            let cols = unfold4d(padded, [3, 3], UnfoldOptions::new([1, 1], [0, 0], [1, 1])); // [1, cin*9, L]
            let y = weight.val().unsqueeze::<3>().matmul(cols); // [1, cout, L]
            let loss = y.sum();
            let _grads = loss.backward();
            let b = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let _grads = conv.forward(x5.clone()).sum().backward();
            let c = t.elapsed().as_secs_f64();
            println!(
                "{cin}->{cout} at {h}x{w}: Conv2d fwd+bwd {a:.3} s (batch 1), {c:.3} s (batch 5, {:.3} s per image); unfold+matmul {b:.3} s",
                c / 5.0
            );
        }
    }
}
