//! Where the cascade's error comes from: every stage's index error against the ground truth on
//! its own grid, and how often the next stage's hypotheses still bracket the truth (a
//! refinement stage can only move within its hypotheses, so a coarse miss stays a miss).
//!
//! `cargo run --release -p omnimvs-train --example cascade_stages -- WEIGHTS DATASET A B`
//!
//! Training ground truth (sky valid at index 0), in inverse-depth index units of N.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::tensor::read_values;
use omnimvs_net::weights::load_cascade;
use omnimvs_train::SampleSource;
use omnimvs_train::augment::RotationSet;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: cascade_stages WEIGHTS DATASET FIRST LAST";
    let weights = PathBuf::from(args.get(1).expect(usage));
    let path = PathBuf::from(args.get(2).expect(usage));
    let first: u32 = args.get(3).expect(usage).parse().unwrap();
    let last: u32 = args.get(4).expect(usage).parse().unwrap();
    let device = Device::flex();
    let net = load_cascade(&weights, &device).unwrap();
    let config = net.config.clone();
    let ds = Dataset::open(&path).unwrap();
    let source = SampleSource::open(&path, &config, RotationSet::new(1, 0.0, 0)).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &config, &source.hypotheses, &device).unwrap();
    let p = &config.cascade;
    // Half-width of the hypotheses of stages 1 and 2 around the previous stage's answer.
    let reach = |stage: usize| {
        (p.stage_hypotheses[stage - 1] - 1) as f32 / 2.0 * p.stage_intervals[stage - 1] as f32
    };
    let names = ["coarse", "half", "full"];
    // Per stage: |error| sum, count, pixels beyond the next stage's reach (sky, index 0,
    // apart), then the sky's |error| sum and count.
    let mut sums = [[0f64; 5]; 3];
    // Per refinement stage, on the pixels within its reach: |centre - truth|, |answer - truth|,
    // count.
    let mut within = [[0f64; 3]; 3];
    // Per stage and ground-truth band (index below 40, 40..80, 80 and above; sky apart): signed
    // error sum, |error| sum, count, and counts of |error| above each of THRESHOLDS.
    const BANDS: [f32; 2] = [40.0, 80.0];
    const THRESHOLDS: [f32; 6] = [2.0, 5.0, 7.5, 10.0, 15.0, 30.0];
    let mut bands = [[[0f64; 3 + THRESHOLDS.len()]; 3]; 3];
    for frame in first..=last {
        let sample = source.load(0, frame, 0, None).unwrap();
        let images = sample.image_tensors([config.input_height, config.input_width], &device);
        let out = net.forward(&images, &geometry).unwrap();
        let truths = [&sample.stage_gt[0], &sample.stage_gt[1], &sample.gt];
        let mut previous: Option<Vec<f32>> = None;
        for (stage, (output, gt)) in out.stages.iter().zip(truths).enumerate() {
            let index = read_values(output.index.clone(), "index").unwrap();
            // What refinement did where it could: the previous stage's answer, upsampled (the
            // centre of this stage's hypotheses), against this stage's, on the pixels whose
            // truth the hypotheses bracket.
            if let Some(prev) = previous.take() {
                let from = geometry.samplers[stage - 1].grid();
                let center =
                    omnimvs_sweep::resample_map(&prev, from, geometry.samplers[stage].grid());
                for (((&n, &c), &t), &v) in index.iter().zip(&center).zip(&gt.index).zip(&gt.valid)
                {
                    if v && t > 0.0 && (c - t).abs() <= reach(stage) {
                        within[stage][0] += f64::from((c - t).abs());
                        within[stage][1] += f64::from((n - t).abs());
                        within[stage][2] += 1.0;
                    }
                }
            }
            previous = Some(index.clone());
            for ((&n, &t), &v) in index.iter().zip(&gt.index).zip(&gt.valid) {
                if !v {
                    continue;
                }
                let e = (n - t).abs();
                if t <= 0.0 {
                    sums[stage][3] += f64::from(e);
                    sums[stage][4] += 1.0;
                    continue;
                }
                sums[stage][0] += f64::from(e);
                sums[stage][1] += 1.0;
                let band = BANDS.iter().filter(|&&b| t >= b).count();
                let b = &mut bands[stage][band];
                b[0] += f64::from(n - t);
                b[1] += f64::from(e);
                b[2] += 1.0;
                for (k, &th) in THRESHOLDS.iter().enumerate() {
                    if e > th {
                        b[3 + k] += 1.0;
                    }
                }
                if stage < 2 && e > reach(stage + 1) + 0.5 {
                    sums[stage][2] += 1.0;
                }
            }
        }
        println!("frame {frame} done");
    }
    for (stage, s) in sums.iter().enumerate() {
        let beyond = if stage < 2 {
            format!(
                "  beyond the next stage's reach (+-{:.1}): {:.1}%",
                reach(stage + 1),
                100.0 * s[2] / s[1]
            )
        } else {
            String::new()
        };
        println!(
            "{:6} MAE {:.2} over {} pixels{beyond}; sky MAE {:.2} over {} pixels",
            names[stage],
            s[0] / s[1],
            s[1],
            s[3] / s[4].max(1.0),
            s[4]
        );
        if stage > 0 {
            let w = within[stage];
            println!(
                "       within reach ({:.1}% of the pixels): centre MAE {:.2} -> answer MAE {:.2}",
                100.0 * w[2] / s[1],
                w[0] / w[2],
                w[1] / w[2]
            );
        }
    }
    println!(
        "non-sky pixels by ground-truth index band: bias (answer - truth), MAE, share of the \
         stage's pixels, % with |error| above {THRESHOLDS:?}"
    );
    for (stage, per_band) in bands.iter().enumerate() {
        let total: f64 = per_band.iter().map(|b| b[2]).sum();
        for (band, b) in per_band.iter().enumerate() {
            let range = match band {
                0 => format!("0..{}", BANDS[0]),
                1 => format!("{}..{}", BANDS[0], BANDS[1]),
                _ => format!("{}..", BANDS[1]),
            };
            let over: Vec<String> = b[3..]
                .iter()
                .map(|c| format!("{:.1}", 100.0 * c / b[2].max(1.0)))
                .collect();
            println!(
                "{:6} {range:>7}  bias {:+.2}  MAE {:.2}  share {:.1}%  over {}",
                names[stage],
                b[0] / b[2].max(1.0),
                b[1] / b[2].max(1.0),
                100.0 * b[2] / total.max(1.0),
                over.join(" / ")
            );
        }
    }
}
