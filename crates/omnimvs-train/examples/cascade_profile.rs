//! Profiles the cascade at full size on one real or generated frame: forward pass per stage
//! (inference mode) and training steps (forward, backward, optimiser).
//!
//! `cargo run --release -p omnimvs-train --example cascade_profile -- DATASET [FRAME] [STEPS]
//! [WINDOW]` (WINDOW: train on that many output columns of longitude, see
//! `omnimvs train --column-window`)
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::time::Instant;

use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::{CascadeGeometry, CascadeInference};
use omnimvs_net::{CascadeNet, NetConfig};
use omnimvs_train::augment::RotationSet;
use omnimvs_train::{Learner, Optimizer, SampleSource, TrainConfig};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = PathBuf::from(
        args.get(1)
            .expect("usage: cascade_profile DATASET [FRAME] [STEPS]"),
    );
    let frame: u32 = args.get(2).map_or(1, |f| f.parse().unwrap());
    let steps: usize = args.get(3).map_or(3, |s| s.parse().unwrap());
    let window: Option<usize> = args.get(4).map(|s| s.parse().unwrap());
    let config = NetConfig::cascade();
    let device = Device::flex();
    let ds = Dataset::open(&path).unwrap();
    let images = ds.read_frame(frame).unwrap();

    let net = CascadeNet::new(&config, &device).unwrap();
    let start = Instant::now();
    let inference = CascadeInference::new(net, &ds, device.clone(), true).unwrap();
    println!("geometry: {:.3} s", start.elapsed().as_secs_f64());
    for _ in 0..2 {
        let mut t = omnimvs_data::StageTimes::default();
        inference.run(&images, &mut t).unwrap();
        println!(
            "forward: features {:.3}  coarse {:.3}  mid {:.3}  fine {:.3}  total {:.3} s",
            t.get("features"),
            t.get("coarse"),
            t.get("mid"),
            t.get("fine"),
            t.get("total")
        );
    }

    // The coarse stage in parts: correlation volume, then the 2D encoder-decoder.
    let net = CascadeNet::new(&config, &device).unwrap();
    let geometry =
        CascadeGeometry::new(&ds.rig, &config, &ds.hypotheses(192).unwrap(), &device).unwrap();
    let [_, _, s8] = config.cascade_feature_sizes();
    let features: Vec<_> = (0..4)
        .map(|_| {
            burn::tensor::Tensor::<4>::random(
                [1, config.cascade.feature_channels[2], s8[0], s8[1]],
                burn::tensor::Distribution::Default,
                &device,
            )
        })
        .collect();
    for _ in 0..2 {
        let t0 = Instant::now();
        let volume = CascadeNet::correlation(&features, &geometry.coarse, 8).unwrap();
        let _ = device.sync();
        let t1 = Instant::now();
        let [b, c, k, h, w] = volume.dims();
        let scores = net.coarse.forward(volume.reshape([b, c * k, h, w]));
        let _ = device.sync();
        let t2 = Instant::now();
        drop(scores);
        println!(
            "coarse parts: correlation {:.3}  regulariser {:.3} s",
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64()
        );
    }

    let train = TrainConfig {
        net: config.clone(),
        optimizer: Optimizer::Adam,
        ..TrainConfig::default()
    };
    let mut learner = Learner::<CascadeNet>::for_model(&train, &device).unwrap();
    let source = SampleSource::open(&path, &config, RotationSet::new(1, 0.0, 0)).unwrap();
    let mut sample = source.load(0, frame, 0, None).unwrap();
    sample.window = window.map(|width| omnimvs_net::cascade::ColumnWindow { start: 100, width });
    let geometry =
        CascadeGeometry::new(&ds.rig, &config, &source.hypotheses, &learner.device).unwrap();
    for _ in 0..steps {
        let t0 = Instant::now();
        let loss = learner.loss(&sample, &geometry, &[]).unwrap();
        let value = loss.clone().into_scalar::<f32>();
        let t1 = Instant::now();
        let grads = burn::optim::GradientsParams::from_grads(loss.backward(), &learner.net);
        let t2 = Instant::now();
        learner.net = learner.optim.step(0.001, learner.net.clone(), grads);
        let _ = learner.device.sync();
        let t3 = Instant::now();
        println!(
            "train step: forward+loss {:.3}  backward {:.3}  optimiser {:.3}  total {:.3} s (loss {value:.3})",
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64(),
            (t3 - t2).as_secs_f64(),
            (t3 - t0).as_secs_f64()
        );
    }
}
