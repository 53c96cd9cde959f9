#![allow(clippy::expect_used)]
//! Lookup-table build and warping at the paper's full size.
//!
//! `cargo bench -p omnimvs-sweep --bench bench_sweep`
//!
//! Needs `../shared/data/omnimvs-samples/sunny_single/config.yaml` (the
//! published 4-camera rig, 768x800 images).

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet};

fn sunny_config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/sunny_single/config.yaml")
}

fn bench(c: &mut Criterion) {
    let rig = omnimvs_camera::read_config_rig(&sunny_config()).expect("sunny_single config");
    let grid = EquirectGrid::new(160, 640, 45.0).expect("grid");
    let hyps = InvDepthHypotheses::new(192, 1.65).expect("hypotheses");
    let mut g = c.benchmark_group("sweep");
    g.sample_size(10);
    g.bench_function("lut_build_4cam_160x640_N192_half", |b| {
        b.iter(|| LookupTable::build(&rig, &grid, &hyps, SphereSet::EveryOther).expect("build"))
    });
    let lut = LookupTable::build(&rig, &grid, &hyps, SphereSet::EveryOther).expect("build");
    let (w, h) = (800usize, 768usize);
    let img: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 255) as f32).collect();
    let mut out = vec![0f32; lut.num_spheres() * grid.len()];
    g.bench_function("warp_800x768_onto_96_spheres_160x640", |b| {
        b.iter(|| {
            omnimvs_sweep::warp_camera_onto_spheres(&lut, 0, &img, 1, w, h, &mut out).expect("warp")
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
