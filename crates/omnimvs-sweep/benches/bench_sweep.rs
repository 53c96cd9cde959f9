#![allow(clippy::expect_used)]
//! Lookup-table build and warping at the paper's full size.
//!
//! `cargo bench -p omnimvs-sweep --bench bench_sweep`
//!
//! Needs `../shared/data/omnimvs-samples/sunny_single/config.yaml` (the
//! published 4-camera rig, 768x800 images). The table is also built for the
//! same rig with double sphere and Kannala-Brandt lenses of about the same
//! image circle (220 degrees over 768 rows), to compare the camera models.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use omnimvs_camera::{CameraModel, CentralCamera, DoubleSphere, KannalaBrandt4, Lens, Rig};
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet};

fn sunny_config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/sunny_single/config.yaml")
}

/// `rig` with every camera's model replaced by `lens` on 800x768 images seeing 220 degrees.
fn with_lens(rig: &Rig, lens: Lens) -> Rig {
    let mut rig = rig.clone();
    for camera in &mut rig.cameras {
        camera.model = CameraModel::Central(
            CentralCamera::new(lens.clone(), 800, 768, Some(220.0)).expect("lens sees 220 deg"),
        );
    }
    rig
}

fn bench(c: &mut Criterion) {
    let rig = omnimvs_camera::read_config_rig(&sunny_config()).expect("sunny_single config");
    let grid = EquirectGrid::new(160, 640, 45.0).expect("grid");
    let hyps = InvDepthHypotheses::new(192, 1.65).expect("hypotheses");
    // 110 degrees from the axis land about 384 px from the centre.
    let ds = DoubleSphere::new(177.0, 177.0, 399.5, 383.5, -0.2, 0.6).expect("ds");
    let kb4 = KannalaBrandt4::new(200.0, 200.0, 399.5, 383.5, -0.01, 0.002, 0.0, 0.0).expect("kb4");
    let rigs = [
        ("lut_build_4cam_160x640_N192_half", rig.clone()),
        (
            "lut_build_4cam_160x640_N192_half_ds",
            with_lens(&rig, Lens::DoubleSphere(ds)),
        ),
        (
            "lut_build_4cam_160x640_N192_half_kb4",
            with_lens(&rig, Lens::KannalaBrandt4(kb4)),
        ),
    ];
    let mut g = c.benchmark_group("sweep");
    g.sample_size(10);
    for (name, rig) in &rigs {
        g.bench_function(*name, |b| {
            b.iter(|| LookupTable::build(rig, &grid, &hyps, SphereSet::EveryOther).expect("build"))
        });
    }
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
