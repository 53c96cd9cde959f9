//! The coarse modes' part of a learnt pick's inputs, for its training data (stop 42,
//! `models/training/pick-7/`): runs the bundled cascade without a pick (as `omnimvs infer
//! --pick off` does) on a dataset's frames and writes, per frame, `FRAME.f32` (raw
//! little-endian `f32`, `[channels, 160, 640]`): the channels that `PickLayout::coarse_modes`
//! adds to the inputs (`4 k + 2`), then the `k` modes' depths (the candidates it adds). The
//! other channels are pick-2's layout, which `models/training/pick-1/pick_inputs.py` computes.
//!
//! `cargo run --release -p omnimvs-net --example pick_modes_data -- DATASET FIRST LAST OUT [K]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use burn::tensor::Device;
use omnimvs_data::{Dataset, StageTimes};
use omnimvs_net::bundled::BundledModel;
use omnimvs_net::cascade::PixelSampler;
use omnimvs_net::estimator::NetEstimator;
use omnimvs_net::pick::PickLayout;
use omnimvs_sweep::LutCache;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: pick_modes_data DATASET FIRST LAST OUT [K]";
    let path = PathBuf::from(args.get(1).expect(usage));
    let first: u32 = args.get(2).expect(usage).parse().unwrap();
    let last: u32 = args.get(3).expect(usage).parse().unwrap();
    let out = PathBuf::from(args.get(4).expect(usage));
    let k: usize = args.get(5).map_or(3, |v| v.parse().unwrap());
    std::fs::create_dir_all(&out).unwrap();
    let device = Device::flex();
    let ds = Dataset::open(&path).unwrap();
    let net = BundledModel::Cascade.load(&device).unwrap();
    let (estimator, _) = NetEstimator::new(
        net,
        &ds,
        &LutCache::new(std::env::temp_dir()),
        device,
        false,
    )
    .unwrap();
    let NetEstimator::Cascade(picked) = estimator else {
        panic!("the bundled model is a cascade");
    };
    let layout = PickLayout {
        coarse_modes: k,
        ..PickLayout::default()
    };
    let inference = picked.inference();
    let sampler = PixelSampler::new(&ds.rig, inference.grid(), inference.hypotheses()).unwrap();
    for frame in first..=last {
        let dst = out.join(format!("{frame:05}.f32"));
        if dst.exists() {
            continue;
        }
        let images = ds.read_frame(frame).unwrap();
        let (est, modes) = picked
            .run_with_modes(&images, &mut StageTimes::default(), k)
            .unwrap();
        let spread = est.spread.clone().unwrap();
        let inputs = layout
            .inputs(&est.index, &spread, &modes, &sampler, &images)
            .unwrap();
        let plane = est.index.len();
        let mode_first = layout.input_channels(images.len()) - layout.mode_channels();
        let mut values = inputs[mode_first * plane..].to_vec();
        values.extend_from_slice(&modes.index);
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        omnimvs_camera::fs::write_atomic(&dst, &bytes).unwrap();
        println!("frame {frame} written");
    }
}
