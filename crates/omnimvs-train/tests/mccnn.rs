#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The matching-cost network's training step: gradients reach every layer, and a fixed batch
//! of patch pairs (positives: a patch and a noisy copy; negatives: unrelated patches) is
//! overfit.

use burn::module::Module;
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::Device;
use omnimvs_core::rng::SplitMix64;
use omnimvs_net::mccnn::{McCnn, McCnnConfig};
use omnimvs_train::mccnn::batch_loss;

/// `4 b` patches: positive A, positive B (A plus noise), negative A, negative B (unrelated).
fn pairs(b: usize, p: usize, seed: u64) -> Vec<f32> {
    let mut rng = SplitMix64::new(seed);
    let mut g = || (rng.next_f64() * 2.0 - 1.0) as f32;
    let n = b * p * p;
    let a: Vec<f32> = (0..n).map(|_| g()).collect();
    let a_noisy: Vec<f32> = a.iter().map(|v| v + 0.2 * g()).collect();
    let c: Vec<f32> = (0..n).map(|_| g()).collect();
    let d: Vec<f32> = (0..n).map(|_| g()).collect();
    [a, a_noisy, c, d].concat()
}

#[test]
fn gradients_reach_every_layer() {
    let device = Device::flex().autodiff();
    device.seed(3);
    let net = McCnn::new(&McCnnConfig::default(), &device).unwrap();
    let (loss, _) = batch_loss(&net, pairs(8, 9, 1), 1.0, &device);
    let grads = loss.backward();
    for (l, conv) in net.convs.iter().enumerate() {
        let g = conv.weight.grad(&grads).expect("a gradient");
        let sum = g.abs().sum().into_scalar::<f32>();
        assert!(sum > 0.0 && sum.is_finite(), "layer {l}: |grad| {sum}");
    }
}

#[test]
fn overfits_a_fixed_batch() {
    let device = Device::flex().autodiff();
    device.seed(5);
    let config = McCnnConfig {
        hidden: 16,
        features: 8,
        ..McCnnConfig::default()
    };
    let mut net = McCnn::new(&config, &device).unwrap();
    let mut optim = AdamConfig::new().init();
    let batch = pairs(32, 9, 7);
    let (first, _) = batch_loss(&net, batch.clone(), 0.2, &device);
    let first = first.into_scalar::<f32>();
    let mut acc = 0.0;
    let mut last = first;
    for _ in 0..60 {
        let (loss, a) = batch_loss(&net, batch.clone(), 0.2, &device);
        last = loss.clone().into_scalar::<f32>();
        acc = a;
        let grads = GradientsParams::from_grads(loss.backward(), &net);
        net = optim.step(1e-2, net.clone(), grads);
    }
    assert!(last < 0.25 * first, "loss {first} -> {last}");
    assert!(acc > 0.95, "ranking accuracy {acc}");
    let _ = net.valid();
}
