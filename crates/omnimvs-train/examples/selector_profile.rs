//! Times the pieces of the full-resolution learnt upsampling (`convex_upsampling_full`) on one
//! frame: candidates, their projection, the photometric cue, the rest of the taps, the
//! correlation and the selector's convolutions; beside them the full-resolution stage.
//!
//! `cargo run --release -p omnimvs-train --example selector_profile -- WEIGHTS DATASET [FRAME]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;
use std::time::Instant;

use burn::tensor::{Device, Tensor};
use omnimvs_data::Dataset;
use omnimvs_net::cascade::model::{UPSAMPLE_TAPS, bilinear_prior, upsampling_candidates};
use omnimvs_net::cascade::photo::ImagePyramid;
use omnimvs_net::cascade::{CascadeGeometry, CascadeNet, StageTaps};
use omnimvs_net::infer::input_tensors;
use omnimvs_net::tensor::read_values;
use omnimvs_net::weights;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, w, d, rest @ ..] = args.as_slice() else {
        panic!("usage: selector_profile WEIGHTS DATASET [FRAME]");
    };
    let frame: u32 = rest.first().map_or(1, |f| f.parse().unwrap());
    let device = Device::flex();
    let net = weights::load_cascade(&PathBuf::from(w), &device)
        .unwrap()
        .fold_batch_norm();
    let ds = Dataset::open(&PathBuf::from(d)).unwrap();
    let config = net.config.clone();
    let geometry = CascadeGeometry::with_host_correlation(
        &ds.rig,
        &config,
        &ds.hypotheses(config.num_invdepth).unwrap(),
        &device,
        true,
    )
    .unwrap();
    let images = ds.read_frame(frame).unwrap();
    let inputs = input_tensors(&config, &images, &ds.masks().unwrap(), &device).unwrap();
    let out = net.forward(&inputs, &geometry).unwrap();
    let mid = read_values(out.stages[1].index.clone(), "mid").unwrap();
    let photo = ImagePyramid::from_inputs(&inputs).unwrap();
    let levels = net.features.forward(Tensor::cat(inputs.clone(), 0));
    let fine_features: Vec<_> = (0..4).map(|c| levels[0].clone().narrow(0, c, 1)).collect();
    let from = *geometry.samplers[1].grid();
    let fine_grid = *geometry.samplers[2].grid();
    let cols = 0..fine_grid.width;
    let selector = net
        .selector(0)
        .expect("a network with the full-resolution selector");
    let mut rows: Vec<[f64; 9]> = Vec::new();
    for _ in 0..7 {
        let t = Instant::now();
        let candidates = upsampling_candidates(&mid, [from.height, from.width], &cols);
        let t_cand = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let grids = geometry.samplers[2]
            .grids_window(&candidates, UPSAMPLE_TAPS, cols.clone())
            .unwrap();
        let t_proj = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let _cue = photo.zncc(0, &grids).unwrap();
        let t_zncc = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let feature_size = config.cascade_feature_sizes()[0];
        let _taps =
            StageTaps::new(&grids, candidates.clone(), feature_size, true, &device).unwrap();
        let t_bilinear = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let taps = geometry
            .taps_for(
                2,
                candidates.clone(),
                UPSAMPLE_TAPS,
                cols.clone(),
                Some(&photo),
            )
            .unwrap();
        let t_taps = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let volume =
            CascadeNet::correlation(&fine_features, &taps, config.cascade.groups[0]).unwrap();
        let _ = device.sync();
        let t_corr = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let prior = bilinear_prior(fine_grid.height, &cols, &device);
        let volume = Tensor::cat(vec![volume, taps.cue.clone().unwrap()], 1);
        let [b, c, k, h, ww] = volume.dims();
        let logits = selector.forward(volume.reshape([b, c * k, h, ww])) + prior;
        let _ = read_values(logits, "logits").unwrap();
        let t_conv = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let stage_taps = geometry
            .refine_taps(2, &mid, cols.clone(), Some(&photo))
            .unwrap();
        let t_stage_taps = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let fine = net.refine_stage(0, &fine_features, &stage_taps).unwrap();
        let _ = read_values(fine.index, "fine").unwrap();
        let t_stage = t.elapsed().as_secs_f64();
        rows.push([
            t_cand,
            t_proj,
            t_zncc,
            t_bilinear,
            t_taps,
            t_corr,
            t_conv,
            t_stage_taps,
            t_stage,
        ]);
    }
    let names = [
        "selector: candidates",
        "selector: projection",
        "selector: cue",
        "selector: bilinear taps (StageTaps::new)",
        "selector: taps in all (projection, cue, bilinear taps)",
        "selector: correlation",
        "selector: convolutions",
        "full stage: taps",
        "full stage: correlation and regulariser",
    ];
    println!("{} rounds; seconds, minimum and median", rows.len());
    for (i, name) in names.iter().enumerate() {
        let mut t: Vec<f64> = rows.iter().map(|r| r[i]).collect();
        t.sort_by(f64::total_cmp);
        println!("{name:<56} {:.4}  {:.4}", t[0], t[t.len() / 2]);
    }
}
