//! Micro-benchmark of the gather primitives on flex.
#![allow(clippy::unwrap_used)]
use std::time::Instant;

use burn::tensor::{Device, Distribution, Int, Tensor, TensorData};

fn main() {
    let device = Device::flex();
    let s = 48 * 40 * 160;
    let table = Tensor::<2>::random([9600, 32], Distribution::Default, &device);
    let idx: Vec<i64> = (0..s).map(|i| ((i as i64) * 31) % 9600).collect();
    let index = Tensor::<1, Int>::from_data(TensorData::new(idx, [s]), &device);
    let w = Tensor::<2>::random([s, 1], Distribution::Default, &device);
    for _ in 0..3 {
        let t = Instant::now();
        let out = table.clone().select(0, index.clone());
        let _ = device.sync();
        let t1 = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let out2 = out.clone() * w.clone();
        let _ = device.sync();
        let t2 = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let out3 = out2.clone() + out.clone();
        let _ = device.sync();
        let t3 = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let sq = out3.clone().powi_scalar(2);
        let _ = device.sync();
        let t4 = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let m = sq.reshape([s, 8, 4]).mean_dim(2);
        let _ = device.sync();
        let t5 = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let tr = m.reshape([s, 8]).swap_dims(0, 1).reshape([8 * s]).sum();
        let _ = device.sync();
        let t6 = t.elapsed().as_secs_f64();
        drop(tr);
        println!(
            "select {t1:.3} mul-bcast {t2:.3} add {t3:.3} powi {t4:.3} groupmean {t5:.3} swap+sum {t6:.3}"
        );
    }
}
