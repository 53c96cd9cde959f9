//! How far the cascade's refinement stages carry another method's answer: the trained network
//! run with its half-resolution stage centred on (a) its own coarse answer, (b) a seed read
//! from another method's output folder (ZNCC+SGM's, say: `%05d.tiff`, inverse depth in 1/m,
//! on any equirectangular grid over the network's latitudes), resampled to the coarse grid,
//! and (c) per coarse pixel whichever of the two is nearer the truth (an oracle: the bound on
//! what a learnt choice between them could reach). Each is scored on the full-resolution
//! grid against the training ground truth, sky (index 0) left out as the reference's rules
//! do; the seed's own answer, resampled to the output grid, is scored beside them.
//!
//! `cargo run --release -p omnimvs-train --example cascade_seeded -- WEIGHTS DATASET SEED_DIR A B`
//!
//! Errors are in inverse-depth index units of N.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use burn::tensor::Device;
use omnimvs_data::gt::read_tiff_f32;
use omnimvs_net::cascade::{CascadeGeometry, SeedChoice};
use omnimvs_net::tensor::read_values;
use omnimvs_net::weights::load_cascade;
use omnimvs_sweep::{EquirectGrid, resample_map};
use omnimvs_train::SampleSource;
use omnimvs_train::augment::RotationSet;

#[path = "support/score.rs"]
mod score;
use score::Score;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: cascade_seeded WEIGHTS DATASET SEED_DIR FIRST LAST";
    let weights = PathBuf::from(args.get(1).expect(usage));
    let path = PathBuf::from(args.get(2).expect(usage));
    let seed_dir = PathBuf::from(args.get(3).expect(usage));
    let first: u32 = args.get(4).expect(usage).parse().unwrap();
    let last: u32 = args.get(5).expect(usage).parse().unwrap();
    let device = Device::flex();
    let net = load_cascade(&weights, &device).unwrap();
    let config = net.config.clone();
    let source = SampleSource::open(&path, &config, RotationSet::new(1, 0.0, 0)).unwrap();
    let rig = source.dataset.rig.clone();
    let geometry = CascadeGeometry::new(&rig, &config, &source.hypotheses, &device).unwrap();
    let coarse_grid = *geometry.samplers[0].grid();
    let fine_grid = *geometry.samplers[2].grid();
    let names = ["own coarse answer", "seed", "nearer of the two (oracle)"];
    let choices = [SeedChoice::Joint, SeedChoice::Peak, SeedChoice::Mass];
    let mut scores = [Score::default(); 3];
    let mut seeded = [Score::default(); 3];
    let mut seed_alone = Score::default();
    let mut coarse_scores = [Score::default(); 3];
    for frame in first..=last {
        let sample = source.load(0, frame, 0, None).unwrap();
        let images = sample.image_tensors([config.input_height, config.input_width], &device);
        let seed_file = seed_dir.join(format!("{frame:05}.tiff"));
        let seed_map = read_tiff_f32(&seed_file).unwrap();
        let seed_grid = EquirectGrid::new(seed_map.height, seed_map.width, config.phi_deg).unwrap();
        let seed_index: Vec<f32> = seed_map
            .data
            .iter()
            .map(|&d| source.hypotheses.index(f64::from(d)).max(0.0) as f32)
            .collect();
        let seed_fine = resample_map(&seed_index, &seed_grid, &fine_grid);
        seed_alone.add(&seed_fine, &sample.gt.index, &sample.gt.valid);
        let seed_coarse = resample_map(&seed_index, &seed_grid, &coarse_grid);
        let coarse_truth = &sample.stage_gt[0];
        for (variant, score) in scores.iter_mut().enumerate() {
            let mut centres_used = Vec::new();
            let out = net
                .forward_with_centres(&images, &geometry, |own| {
                    let centres: Vec<f32> = match variant {
                        0 => own.to_vec(),
                        1 => seed_coarse.clone(),
                        _ => own
                            .iter()
                            .zip(&seed_coarse)
                            .zip(&coarse_truth.index)
                            .map(
                                |((&a, &b), &t)| if (a - t).abs() <= (b - t).abs() { a } else { b },
                            )
                            .collect(),
                    };
                    centres_used = centres.clone();
                    Ok(centres)
                })
                .unwrap();
            coarse_scores[variant].add(&centres_used, &coarse_truth.index, &coarse_truth.valid);
            let [_, _, fine] = out.stages;
            let index = read_values(fine.index, "index").unwrap();
            score.add(&index, &sample.gt.index, &sample.gt.valid);
        }
        for (choice, score) in choices.iter().zip(&mut seeded) {
            let out = net
                .forward_seeded(&images, &geometry, &seed_coarse, *choice)
                .unwrap();
            let [_, _, fine] = out.stages;
            let index = read_values(fine.index, "index").unwrap();
            score.add(&index, &sample.gt.index, &sample.gt.valid);
        }
        println!("frame {frame} done");
    }
    println!("centres on the coarse grid:");
    for (name, score) in names.iter().zip(&coarse_scores) {
        println!("  {}", score.line(name));
    }
    println!("the cascade's final answer, half-resolution stage centred on:");
    for (name, score) in names.iter().zip(&scores) {
        println!("  {}", score.line(name));
    }
    println!("the half-resolution stage run around both, then:");
    for (choice, score) in choices.iter().zip(&seeded) {
        println!("  {}", score.line(&format!("{choice:?}")));
    }
    println!("the seed alone, at the output grid:");
    println!("  {}", seed_alone.line(&seed_dir.display().to_string()));
}
