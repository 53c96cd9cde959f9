#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The whole method and its stages at the paper's size: four 768x800
//! fisheye images of generated rooms (`omnimvs-synth`), a 160x640 output, N = 192.
//!
//! `RAYON_NUM_THREADS=2 cargo bench -p omnimvs-stereo --bench bench_sgm`
//!
//! One benchmark per stage: `warp` (projecting every grid pixel of every
//! sphere into every camera that can see it and sampling it, with the matcher's kernels),
//! `warp_and_cost` (the matcher: warp, window sums, ZNCC and the volume in
//! one pass; the cost stage is its time minus `warp`'s), `aggregation_8_paths`
//! and `wta`, then the whole method. The stage split of one frame is printed
//! before the measurements (the `full_size` study, `research/study-programs.md`,
//! printed it per frame with the CPU time and peak memory).

#[path = "../tests/support/scenes.rs"]
mod scenes;

use criterion::{Criterion, criterion_group, criterion_main};

use omnimvs_stereo::{
    CameraView, Matcher, RunSampler, SgmParams, SphericalStereo, SweepStep, aggregate_in,
    winner_take_all,
};
use omnimvs_sweep::SphereProjector;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use rayon::prelude::*;
use scenes::{Rendered, published_rig, room};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let rig = published_rig(1.0);
    let grid = EquirectGrid::new(160, 640, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(192, 1.0).unwrap();
    let stereo = SphericalStereo::new(&rig, grid, hyps, SgmParams::default()).unwrap();
    let images = Rendered::new(&room(&rig, 2000), &rig).images;
    let t = stereo.compute(&images, None).unwrap().timings;
    eprintln!(
        "stages of one frame ({} threads): warp {:.3} s, cost {:.3} s, aggregation {:.3} s, wta {:.3} s, total {:.3} s",
        rayon::current_num_threads(),
        t.warp_s,
        t.cost_s,
        t.aggregation_s,
        t.wta_s,
        t.total_s
    );
    let mut g = c.benchmark_group("sgm_4cam_768x800_160x640_N192");
    g.sample_size(10);
    g.bench_function("whole_method", |b| {
        b.iter(|| stereo.compute(&images, None).unwrap())
    });
    let half = SphericalStereo::new(
        &rig,
        grid,
        hyps,
        SgmParams {
            sweep: SweepStep::EveryOther,
            ..SgmParams::default()
        },
    )
    .unwrap();
    g.bench_function("whole_method_every_other_sphere", |b| {
        b.iter(|| half.compute(&images, None).unwrap())
    });
    // The warp alone: every sphere, camera and grid row, as `Matcher::warp_row`.
    let projectors: Vec<SphereProjector> = rig
        .cameras
        .iter()
        .enumerate()
        .map(|(i, c)| SphereProjector::new(c, i + 1, &grid).unwrap())
        .collect();
    let views: Vec<CameraView> = images
        .iter()
        .enumerate()
        .map(|(i, img)| CameraView::new(img, None, i + 1).unwrap())
        .collect();
    // Four consecutive spheres per task, interleaved row by row and camera
    // by camera, as the matcher does (it keeps the images in cache), with its
    // kernels: only the columns a camera can see, positions, taps, texels, blend.
    let (near, far) = (
        hyps.inv_depth(0.0) as f32,
        hyps.inv_depth((hyps.count - 1) as f64) as f32,
    );
    let visible: Vec<Vec<Vec<(usize, usize)>>> = projectors
        .iter()
        .map(|p| {
            (0..grid.height)
                .map(|row| p.visible_runs(row, grid.width, near, far))
                .collect()
        })
        .collect();
    g.bench_function("warp", |b| {
        b.iter(|| {
            let spheres: Vec<usize> = (0..hyps.count).collect();
            spheres
                .par_chunks(4)
                .map(|ns| {
                    let d: Vec<f32> = ns
                        .iter()
                        .map(|&n| hyps.inv_depth(n as f64) as f32)
                        .collect();
                    let w = grid.width;
                    let mut sampler = RunSampler::new(w);
                    let mut acc = 0f32;
                    for row in 0..grid.height {
                        for ((p, v), runs) in projectors.iter().zip(&views).zip(&visible) {
                            for &(a, e) in &runs[row] {
                                for &dn in &d {
                                    let (values, _) = sampler.sample(p, v, row * w + a, e - a, dn);
                                    acc += values.iter().sum::<f32>();
                                }
                            }
                        }
                    }
                    black_box(acc)
                })
                .sum::<f32>()
        })
    });
    // The matcher and SGM in buffers kept from one iteration to the next, as
    // `SphericalStereo` keeps them from frame to frame.
    let matcher = Matcher {
        grid,
        projectors: &projectors,
        views: &views,
        radius: 4,
    };
    let mut buffer = Vec::new();
    g.bench_function("warp_and_cost", |b| {
        b.iter(|| {
            let (v, _) = matcher
                .cost_volume_in(&hyps, SweepStep::All, std::mem::take(&mut buffer))
                .unwrap();
            buffer = v.data;
        })
    });
    let (cost, _) = stereo.cost_volume(&images, None).unwrap();
    let mut buffer = Vec::new();
    g.bench_function("aggregation_8_paths", |b| {
        b.iter(|| {
            let (agg, _) =
                aggregate_in(&cost, &SgmParams::default(), std::mem::take(&mut buffer)).unwrap();
            buffer = agg.data;
        })
    });
    let (agg, _) = stereo.aggregate(&cost).unwrap();
    g.bench_function("wta", |b| b.iter(|| winner_take_all(&agg)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
