//! The scale of each stage's inputs: the group-wise correlations of the learnt features against
//! the photometric cue (ZNCC of the images), on a frame's own stages, to start the cue's weights
//! at the scale of one correlation group (`scripts/cascade/init_cue.py`).
//!
//! `cargo run --release -p omnimvs-train --example cue_scale -- WEIGHTS DATASET A B`
//!
//! Prints, per stage, the standard deviation of the correlation channels and of the cue over
//! frames A..=B.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::photo::ImagePyramid;
use omnimvs_net::cascade::{CascadeGeometry, CascadeNet, ColumnWindow};
use omnimvs_net::tensor::read_values;
use omnimvs_net::weights::load_cascade;
use omnimvs_train::SampleSource;
use omnimvs_train::augment::RotationSet;

/// Standard deviation of `values`.
fn std(values: &[f32]) -> f64 {
    let n = values.len() as f64;
    let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    (values
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: cue_scale WEIGHTS DATASET FIRST LAST";
    let weights = PathBuf::from(args.get(1).expect(usage));
    let path = PathBuf::from(args.get(2).expect(usage));
    let first: u32 = args.get(3).expect(usage).parse().unwrap();
    let last: u32 = args.get(4).expect(usage).parse().unwrap();
    let device = Device::flex();
    let net = load_cascade(&weights, &device).unwrap();
    let mut config = net.config.clone();
    config.cascade.zncc_cue = true;
    let ds = Dataset::open(&path).unwrap();
    let source = SampleSource::open(&path, &config, RotationSet::new(1, 0.0, 0)).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &config, &source.hypotheses, &device).unwrap();
    let p = &config.cascade;
    let names = ["coarse", "half", "full"];
    let mut corr: [Vec<f32>; 3] = Default::default();
    let mut cue: [Vec<f32>; 3] = Default::default();
    let whole = ColumnWindow {
        start: 0,
        width: config.out_width,
    };
    for frame in first..=last {
        let sample = source.load(0, frame, 0, None).unwrap();
        let images = sample.image_tensors([config.input_height, config.input_width], &device);
        let pyramid = ImagePyramid::from_inputs(&images).unwrap();
        let out = net.forward(&images, &geometry).unwrap();
        let levels = net
            .features
            .forward(burn::tensor::Tensor::cat(images.clone(), 0));
        let per_camera = |level: usize| -> Vec<_> {
            (0..images.len())
                .map(|c| levels[level].clone().narrow(0, c, 1))
                .collect()
        };
        // Coarse: fixed spheres.
        let volume =
            CascadeNet::correlation(&per_camera(2), &geometry.coarse, p.groups[2]).unwrap();
        let g = p.groups[2];
        corr[0].extend(read_values(volume.narrow(1, 0, g), "corr").unwrap());
        let c = geometry.coarse_cue(Some(&pyramid)).unwrap().unwrap();
        cue[0].extend(read_values(c, "cue").unwrap());
        // Refinement stages around the network's own previous answers.
        let coarse = read_values(out.stages[0].index.clone(), "index").unwrap();
        let mid = read_values(out.stages[1].index.clone(), "index").unwrap();
        for (stage, previous) in [(1usize, &coarse), (2, &mid)] {
            let taps = geometry
                .refine_taps(stage, previous, whole.scaled(3 - stage), Some(&pyramid))
                .unwrap();
            let level = 2 - stage;
            let g = p.groups[level];
            let volume = CascadeNet::correlation(&per_camera(level), &taps, g).unwrap();
            corr[stage].extend(read_values(volume.narrow(1, 0, g), "corr").unwrap());
            cue[stage].extend(read_values(taps.cue.clone().unwrap(), "cue").unwrap());
        }
    }
    for s in 0..3 {
        println!(
            "{}: correlation std {:.4}, cue std {:.4}, ratio {:.4}",
            names[s],
            std(&corr[s]),
            std(&cue[s]),
            std(&corr[s]) / std(&cue[s])
        );
    }
}
