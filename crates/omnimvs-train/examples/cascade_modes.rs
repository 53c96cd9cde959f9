//! Would a second hypothesis from the coarse stage pay? The trained cascade's coarse
//! distribution over its spheres, per coarse pixel: how often the truth lies within the half
//! stage's reach (+-R index units) of (a) the soft argmax (what the network centres on now),
//! (b) the most probable sphere, (c) either of the two most probable separated modes, (d) any
//! of three; then the whole network with its half stage also run around the second mode
//! (`CascadeNet::forward_seeded`, untrained choices) and with an oracle choice between the two
//! centres. Also, on the half and full grids, how often the truth lies within the stage's
//! reach (+-R, +-2) of its centre: the bilinear upsampling of the previous answer, the parent
//! pixel's answer, any of the 2x2 or 3x3 previous answers around it, and, for a network with
//! learnt upsampling (`convex_upsampling`), the centres it made. Non-sky pixels of the
//! training ground truth, index units of N.
//!
//! `cargo run --release -p omnimvs-train --example cascade_modes -- WEIGHTS DATASET A B [REACH]`
//! (`MODES_ONLY=1` skips the runs around the second mode: the counts only).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use burn::tensor::Device;
use omnimvs_data::gt::GroundTruth;
use omnimvs_net::cascade::{CascadeGeometry, SeedChoice};
use omnimvs_net::tensor::read_values;
use omnimvs_net::weights::load_cascade;
use omnimvs_train::SampleSource;
use omnimvs_train::augment::RotationSet;

#[path = "support/score.rs"]
mod score;
use score::Score;

/// Over the scored pixels of `truth` (sky left out), on a grid of twice the rows and columns
/// of `previous` (`[h, w]`, row-major): how many lie within `reach` of `bilinear` (the
/// previous map upsampled by `resample_map`), of their parent's value, of any of the 2x2
/// previous pixels around their centre, and of any of the 3x3 around their parent; and the
/// number of pixels.
fn reach_counts(
    previous: &[f32],
    [h, w]: [usize; 2],
    bilinear: &[f32],
    truth: &GroundTruth,
    reach: f32,
) -> [f64; 5] {
    let mut counts = [0.0f64; 5];
    let at = |r: i64, c: i64| {
        let r = r.clamp(0, h as i64 - 1) as usize;
        previous[r * w + c.rem_euclid(w as i64) as usize]
    };
    for r in 0..2 * h {
        for c in 0..2 * w {
            let p = r * 2 * w + c;
            let t = truth.index[p];
            if !truth.valid[p] || t <= 0.0 {
                continue;
            }
            let near = |x: f32| (x - t).abs() <= reach;
            let r0 = ((r as f32 + 0.5) / 2.0 - 0.5).floor() as i64;
            let c0 = ((c as f32 + 0.5) / 2.0 - 0.5).floor() as i64;
            let any4 = [(0, 0), (0, 1), (1, 0), (1, 1)]
                .iter()
                .any(|&(a, b)| near(at(r0 + a, c0 + b)));
            let (rp, cp) = ((r / 2) as i64, (c / 2) as i64);
            let any9 = (-1..=1).any(|a| (-1..=1).any(|b| near(at(rp + a, cp + b))));
            for (count, hit) in
                counts
                    .iter_mut()
                    .zip([near(bilinear[p]), near(at(rp, cp)), any4, any9, true])
            {
                *count += f64::from(u8::from(hit));
            }
        }
    }
    counts
}

/// The `count` most probable modes of one pixel's distribution over `k` spheres: the best
/// sphere, then the best one at least `gap` spheres from every mode taken so far.
fn modes(prob: &[f32], hyp: &[f32], gap: usize, count: usize) -> Vec<f32> {
    let mut taken: Vec<usize> = Vec::new();
    for _ in 0..count {
        let best = (0..prob.len())
            .filter(|&i| taken.iter().all(|&t| i.abs_diff(t) >= gap))
            .max_by(|&a, &b| prob[a].total_cmp(&prob[b]));
        match best {
            Some(b) => taken.push(b),
            None => break,
        }
    }
    taken.iter().map(|&i| hyp[i]).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: cascade_modes WEIGHTS DATASET FIRST LAST [REACH]";
    let weights = PathBuf::from(args.get(1).expect(usage));
    let path = PathBuf::from(args.get(2).expect(usage));
    let first: u32 = args.get(3).expect(usage).parse().unwrap();
    let last: u32 = args.get(4).expect(usage).parse().unwrap();
    let reach: f32 = args.get(5).map_or(7.0, |r| r.parse().unwrap());
    let device = Device::flex();
    let net = load_cascade(&weights, &device).unwrap();
    let config = net.config.clone();
    let source = SampleSource::open(&path, &config, RotationSet::new(1, 0.0, 0)).unwrap();
    let geometry =
        CascadeGeometry::new(&source.dataset.rig, &config, &source.hypotheses, &device).unwrap();
    // Within reach: soft argmax, top mode, top 2, top 3; pixels.
    let mut within = [0.0f64; 5];
    // Within reach on the half and full grids: bilinear, parent, 2x2, 3x3; pixels.
    let mut mid_within = [0.0f64; 5];
    let mut fine_within = [0.0f64; 5];
    let modes_only = std::env::var("MODES_ONLY").is_ok();
    let mut learnt_within = [[0.0f64; 2]; 2];
    let names = [
        "own coarse answer",
        "second mode",
        "nearer of the two (oracle)",
    ];
    let mut scores = [Score::default(); 3];
    let choices = [SeedChoice::Joint, SeedChoice::Peak, SeedChoice::Mass];
    let mut seeded = [Score::default(); 3];
    for frame in first..=last {
        let sample = source.load(0, frame, 0, None).unwrap();
        let images = sample.image_tensors([config.input_height, config.input_width], &device);
        let out = net.forward(&images, &geometry).unwrap();
        let learnt: Vec<Option<Vec<f32>>> = out
            .upsampled
            .iter()
            .map(|u| u.clone().map(|u| read_values(u, "upsampled").unwrap()))
            .collect();
        for ((up, gt), (reach, slot)) in learnt
            .iter()
            .zip([&sample.stage_gt[1], &sample.gt])
            .zip([(reach, 0), (2.0, 1)])
        {
            if let Some(up) = up {
                for ((&u, &t), &v) in up.iter().zip(&gt.index).zip(&gt.valid) {
                    if v && t > 0.0 {
                        learnt_within[slot][1] += 1.0;
                        learnt_within[slot][0] += f64::from(u8::from((u - t).abs() <= reach));
                    }
                }
            }
        }
        let [coarse, half, _] = out.stages;
        let half_index = read_values(half.index, "half index").unwrap();
        let [_, k, h, w] = coarse.prob.dims();
        let prob = read_values(coarse.prob, "prob").unwrap();
        let hyp = read_values(coarse.hypotheses, "hypotheses").unwrap();
        let soft = read_values(coarse.index, "index").unwrap();
        let truth = &sample.stage_gt[0];
        let mut second = vec![0.0f32; h * w];
        for p in 0..h * w {
            let column = |v: &[f32]| (0..k).map(|s| v[s * h * w + p]).collect::<Vec<f32>>();
            let (pp, hh) = (column(&prob), column(&hyp));
            let m = modes(&pp, &hh, 3, 3);
            second[p] = m.get(1).copied().unwrap_or(m[0]);
            let t = truth.index[p];
            if !truth.valid[p] || t <= 0.0 {
                continue;
            }
            let near = |x: f32| (x - t).abs() <= reach;
            within[4] += 1.0;
            within[0] += f64::from(u8::from(near(soft[p])));
            for (c, count) in within.iter_mut().enumerate().take(4).skip(1) {
                *count += f64::from(u8::from(m.iter().take(c).any(|&x| near(x))));
            }
        }
        // On the half grid from the coarse soft argmax (reach +-R), on the full grid from the
        // half stage's answer (reach +-2).
        let grids = geometry.samplers.each_ref().map(|s| *s.grid());
        for ((previous, [from, to]), (gt, (reach, sums))) in [&soft, &half_index]
            .into_iter()
            .zip([[grids[0], grids[1]], [grids[1], grids[2]]])
            .zip(
                [&sample.stage_gt[1], &sample.gt]
                    .into_iter()
                    .zip([(reach, &mut mid_within), (2.0, &mut fine_within)]),
            )
        {
            let bilinear = omnimvs_sweep::resample_map(previous, &from, &to);
            let counts = reach_counts(previous, [from.height, from.width], &bilinear, gt, reach);
            for (sum, count) in sums.iter_mut().zip(counts) {
                *sum += count;
            }
        }
        if modes_only {
            println!("frame {frame} done");
            continue;
        }
        for (variant, score) in scores.iter_mut().enumerate() {
            let out = net
                .forward_with_centres(&images, &geometry, |own| {
                    Ok(match variant {
                        0 => own.to_vec(),
                        1 => second.clone(),
                        _ => own
                            .iter()
                            .zip(&second)
                            .zip(&truth.index)
                            .map(
                                |((&a, &b), &t)| if (a - t).abs() <= (b - t).abs() { a } else { b },
                            )
                            .collect(),
                    })
                })
                .unwrap();
            let [_, _, fine] = out.stages;
            let index = read_values(fine.index, "index").unwrap();
            score.add(&index, &sample.gt.index, &sample.gt.valid);
        }
        for (choice, score) in choices.iter().zip(&mut seeded) {
            let out = net
                .forward_seeded(&images, &geometry, &second, *choice)
                .unwrap();
            let [_, _, fine] = out.stages;
            let index = read_values(fine.index, "index").unwrap();
            score.add(&index, &sample.gt.index, &sample.gt.valid);
        }
        println!("frame {frame} done");
    }
    let n = within[4].max(1.0);
    println!(
        "coarse pixels within +-{reach} of the truth ({} pixels):",
        within[4]
    );
    for (name, x) in ["soft argmax", "top mode", "top 2 modes", "top 3 modes"]
        .iter()
        .zip(&within)
    {
        println!("  {name:20} {:5.1}%", 100.0 * x / n);
    }
    for (grid, reach, counts, previous) in [
        ("half", reach, &mid_within, "coarse"),
        ("full", 2.0, &fine_within, "half"),
    ] {
        let n = counts[4].max(1.0);
        println!(
            "{grid}-grid pixels within +-{reach} of the truth ({} pixels):",
            counts[4]
        );
        let names = [
            "bilinear centre".to_string(),
            format!("nearest {previous}"),
            format!("any of 2x2 {previous}"),
            format!("any of 3x3 {previous}"),
        ];
        for (name, x) in names.iter().zip(counts) {
            println!("  {name:20} {:5.1}%", 100.0 * x / n);
        }
    }
    for (name, [hit, n]) in ["half grid (+-reach)", "full grid (+-2)"]
        .iter()
        .zip(learnt_within)
    {
        if n > 0.0 {
            println!("learnt upsampling, {name}: {:5.1}%", 100.0 * hit / n);
        }
    }
    if modes_only {
        return;
    }
    println!("final answer, half stage centred on:");
    for (name, score) in names.iter().zip(&scores) {
        println!("  {}", score.line(name));
    }
    println!("half stage run around the soft argmax and the second mode, then:");
    for (choice, score) in choices.iter().zip(&seeded) {
        println!("  {}", score.line(&format!("{choice:?}")));
    }
}
