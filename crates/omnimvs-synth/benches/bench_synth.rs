//! One full frame with the published rig: scene generation, BVH build,
//! 4 x 768x800 fisheye images and the 320x640 ground truth.
//!
//! `cargo bench -p omnimvs-synth --bench bench_synth` (target: < 1.5 s per
//! frame at 1 spp on 2 cores). The `spp` group shows how the image time
//! scales with samples per pixel.

#![allow(clippy::unwrap_used, clippy::expect_used)] // benchmark set-up

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::dataset::{GT_HEIGHT, GT_PHI_DEG, GT_WIDTH, render_scene};
use omnimvs_synth::rig::{preset_rig, rig_radius_m};
use omnimvs_synth::{GenParams, SceneKind, Tracer, generate, render_fisheye, render_inverse_depth};

fn bench_frame(c: &mut Criterion) {
    let source = preset_rig().unwrap();
    let params = GenParams::new(source.min_depth_m, rig_radius_m(&source.rig));
    let grid = EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG).unwrap();
    let mut group = c.benchmark_group("frame");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(12));
    for kind in [SceneKind::Things, SceneKind::House] {
        group.bench_function(format!("{}_full_frame_1spp", kind.name()), |b| {
            let mut frame = 0;
            b.iter(|| {
                frame += 1;
                let scene = generate(kind, 0, frame, &params).unwrap();
                black_box(render_scene(&scene, &[], &source.rig, 1, &grid).unwrap())
            });
        });
    }
    group.finish();

    // Parts of one things frame, and samples per pixel.
    let scene = generate(SceneKind::Things, 0, 1, &params).unwrap();
    let mut group = c.benchmark_group("things_parts");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(8));
    group.bench_function("generate_and_build_bvh", |b| {
        b.iter(|| {
            black_box(
                Tracer::new(&generate(SceneKind::Things, 0, 1, &params).unwrap(), &[]).unwrap(),
            )
        })
    });
    let tracer = Tracer::new(&scene, &[]).unwrap();
    group.bench_function("ground_truth_320x640", |b| {
        b.iter(|| black_box(render_inverse_depth(&tracer, &grid)))
    });
    for spp in [1, 2, 4, 8] {
        group.bench_function(format!("four_fisheyes_{spp}spp"), |b| {
            b.iter(|| {
                for cam in &source.rig.cameras {
                    black_box(render_fisheye(&tracer, cam, spp));
                }
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_frame);
criterion_main!(benches);
