//! Properties of generated scenes: nothing closer than the minimum depth,
//! user meshes are placed and traced, rendering does not depend on the
//! number of threads.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)] // helpers of tests

use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::mesh_file::load_mesh;
use omnimvs_synth::rig::{preset_rig, resize_rig, rig_radius_m};
use omnimvs_synth::{
    GenParams, SceneKind, ShapeSpec, Tracer, generate, render_fisheye, render_inverse_depth,
};

fn params() -> GenParams {
    let source = preset_rig().unwrap();
    GenParams::new(source.min_depth_m, rig_radius_m(&source.rig))
}

#[test]
fn no_geometry_is_closer_than_the_minimum_depth() {
    let p = params();
    let grid = EquirectGrid::new(80, 160, 90.0).unwrap();
    let limit = (1.0 / p.clearance_m()) as f32;
    for kind in [SceneKind::Things, SceneKind::House] {
        for frame in 1..=6 {
            let scene = generate(kind, 9, frame, &p).unwrap();
            let gt = render_inverse_depth(&Tracer::new(&scene, &[]).unwrap(), &grid);
            let max = gt.iter().copied().fold(0.0f32, f32::max);
            assert!(
                max <= limit * 1.000_01,
                "{} frame {frame}: inverse depth {max} > {limit}",
                kind.name()
            );
            // Houses are closed up to their windows and doorways.
            if kind == SceneKind::House {
                let finite = gt.iter().filter(|&&v| v > 0.0).count();
                assert!(
                    finite > gt.len() / 2,
                    "house frame {frame}: only {finite} pixels hit geometry"
                );
            }
        }
    }
}

#[test]
fn user_meshes_are_placed_and_traced() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tetra.obj");
    std::fs::write(
        &path,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let mesh = load_mesh(&path).unwrap();
    let mut p = params();
    p.meshes = vec![path.to_string_lossy().into_owned()];
    let scene = generate(SceneKind::Things, 1, 1, &p).unwrap();
    let used = scene
        .objects
        .iter()
        .filter(|o| matches!(o.shape, ShapeSpec::UserMesh { index: 0 }))
        .count();
    assert!(used > 10, "only {used} of 64 objects use the user mesh");
    let with = Tracer::new(&scene, std::slice::from_ref(&mesh)).unwrap();
    let without = Tracer::new(&scene, &[]).err().unwrap().to_string();
    assert!(without.contains("mesh 0"), "{without}");
    assert!(with.num_primitives() >= used * 4);
}

#[test]
fn rendering_is_the_same_with_one_or_two_threads() {
    let p = params();
    let rig = resize_rig(&preset_rig().unwrap().rig, 64, 66).unwrap();
    let scene = generate(SceneKind::House, 2, 1, &p).unwrap();
    let grid = EquirectGrid::new(40, 80, 90.0).unwrap();
    let render = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let tracer = Tracer::new(&scene, &[]).unwrap();
            let imgs: Vec<Vec<u8>> = rig
                .cameras
                .iter()
                .map(|c| render_fisheye(&tracer, c, 2))
                .collect();
            (imgs, render_inverse_depth(&tracer, &grid))
        })
    };
    assert!(render(1) == render(2));
}
