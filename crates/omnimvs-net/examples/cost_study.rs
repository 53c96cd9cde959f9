//! SGM on cached cost volumes: the study behind the penalties and the cost mix of the
//! SweepNet-style cost (issue 15; `models/training/sweepnet/README.md`).
//!
//! Every frame's ZNCC and learned cost volumes (160x640, N = 192) are computed once and kept
//! in `CACHE` (raw `u16`, 39 MB each), then SGM, WTA and the 5x5 median run for every setting
//! `MIX:P1:P2`, whose cost is `MIX * learned + (1 - MIX) * ZNCC`. Prints the reference-rule
//! metrics (mean over frames) of each setting.
//!
//! ```sh
//! cargo run --release -p omnimvs-net --example cost_study -- DATA FIRST LAST CACHE \
//!     WEIGHTS 1:0.05:4 0.5:0.1:2 ...
//! ```
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_data::metrics::{Metrics, Protocol, protocol_metrics};
use omnimvs_stereo::{CostVolume, SgmParams, SphericalStereo, filter, winner_take_all};

fn read_volume(path: &Path, shape: [usize; 3]) -> Option<CostVolume> {
    let bytes = std::fs::read(path).ok()?;
    let data: Vec<u16> = bytes
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    (data.len() == shape.iter().product::<usize>()).then_some(CostVolume {
        height: shape[0],
        width: shape[1],
        ndepth: shape[2],
        data,
    })
}

fn write_volume(path: &Path, v: &CostVolume) {
    let bytes: Vec<u8> = v.data.iter().flat_map(|c| c.to_le_bytes()).collect();
    omnimvs_camera::fs::write_atomic(path, &bytes).unwrap();
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    assert!(
        args.len() >= 7,
        "usage: cost_study DATA FIRST LAST CACHE WEIGHTS MIX:P1:P2..."
    );
    let ds = Dataset::open(Path::new(&args[1])).unwrap();
    let (first, last): (u32, u32) = (args[2].parse().unwrap(), args[3].parse().unwrap());
    let cache = PathBuf::from(&args[4]);
    std::fs::create_dir_all(&cache).unwrap();
    let settings: Vec<(f32, f32, f32)> = args[6..]
        .iter()
        .map(|s| {
            let v: Vec<f32> = s.split(':').map(|x| x.parse().unwrap()).collect();
            (v[0], v[1], v[2])
        })
        .collect();
    let spec = ds.sweep_spec(160, 640, 45.0, 192).unwrap();
    let masks = ds.masks().unwrap();
    let device = Device::flex();
    let net = omnimvs_net::sweepnet::from_name(&args[5], &device).unwrap();
    let learned_patch = 2 * net.config.radii.iter().copied().max().unwrap_or(4) + 1;
    let zncc =
        SphericalStereo::new(&ds.rig, spec.grid, spec.hypotheses, SgmParams::default()).unwrap();
    let learned = SphericalStereo::new(
        &ds.rig,
        spec.grid,
        spec.hypotheses,
        SgmParams {
            patch: learned_patch,
            ..SgmParams::default()
        },
    )
    .unwrap()
    .with_learned_cost(Some(net.learned_cost().unwrap()));
    let shape = [spec.height(), spec.width(), spec.ndepth()];
    let tag = Path::new(&args[1])
        .file_name()
        .unwrap()
        .to_string_lossy()
        .to_string();
    let mut sums = vec![Vec::<Metrics>::new(); settings.len()];
    for frame in first..=last {
        let truth = ds.eval_truth(frame, &spec).unwrap().expect("ground truth");
        let mut volumes = Vec::new();
        for (name, stereo) in [("zncc", &zncc), ("learned", &learned)] {
            let path = cache.join(format!("{tag}_{name}_{frame:05}.u16"));
            let v = match read_volume(&path, shape) {
                Some(v) => v,
                None => {
                    let images = ds.read_frame(frame).unwrap();
                    let (v, _) = stereo.cost_volume(&images, Some(&masks)).unwrap();
                    write_volume(&path, &v);
                    v
                }
            };
            volumes.push(v);
        }
        let mut line = format!("frame {frame}:");
        for (k, &(mix, p1, p2)) in settings.iter().enumerate() {
            let data = volumes[0]
                .data
                .iter()
                .zip(&volumes[1].data)
                .map(|(&z, &l)| (mix * f32::from(l) + (1.0 - mix) * f32::from(z)).round() as u16)
                .collect();
            let cost = CostVolume {
                data,
                ..volumes[0].clone()
            };
            let params = SgmParams {
                p1,
                p2,
                ..SgmParams::default()
            };
            let stereo = SphericalStereo::new(&ds.rig, spec.grid, spec.hypotheses, params).unwrap();
            let (agg, _) = stereo.aggregate(&cost).unwrap();
            let mut index = winner_take_all(&agg);
            index.index = filter::median_filter(&index, params.median);
            let m =
                protocol_metrics(&index.index, &truth, spec.ndepth(), Protocol::Reference).unwrap();
            line += &format!(" {:.2}", m.mae);
            sums[k].push(m);
        }
        println!("{line}");
    }
    println!("| mix | P1 | P2 | >1 | >3 | >5 | MAE | RMS |");
    for (k, &(mix, p1, p2)) in settings.iter().enumerate() {
        let n = sums[k].len() as f64;
        let mean = |f: fn(&Metrics) -> f64| sums[k].iter().map(f).sum::<f64>() / n;
        println!(
            "| {mix} | {p1} | {p2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            mean(|m| m.over1_pct),
            mean(|m| m.over3_pct),
            mean(|m| m.over5_pct),
            mean(|m| m.mae),
            mean(|m| m.rms),
        );
    }
}
