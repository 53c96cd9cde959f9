//! The rendered cameras agree with each other through the ground truth:
//! warping every camera to the panorama with the ground-truth inverse depth
//! gives the same intensities where cameras overlap, and a wrong depth does
//! not.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::needless_range_loop)] // helpers of tests

use glam::Vec3A;
use omnimvs_camera::nalgebra::Vector3;
use omnimvs_core::GrayImage;
use omnimvs_sweep::{EquirectGrid, InvDepthSource, warp_camera_to_panorama};
use omnimvs_synth::rig::{preset_rig, resize_rig, rig_radius_m};
use omnimvs_synth::{
    GenParams, SceneKind, ShapeSpec, Tracer, generate, render_gray_frame, render_inverse_depth,
};

/// Whether camera `cam` sees the ground-truth point of panorama pixel `k`
/// (nothing in between; the sky when the inverse depth is 0).
fn visible(
    tracer: &Tracer,
    cam: &omnimvs_camera::Camera,
    grid: &EquirectGrid,
    inv: &[f32],
    k: usize,
) -> bool {
    let ray = grid.ray((k / grid.width) as f64, (k % grid.width) as f64);
    let c = cam.center_in_rig().coords;
    let to_vec = |v: Vector3<f64>| Vec3A::new(v.x as f32, v.y as f32, v.z as f32);
    if inv[k] <= 0.0 {
        return tracer.intersect(to_vec(c), to_vec(ray)).is_none();
    }
    let p = ray / f64::from(inv[k]);
    let dist = (p - c).norm();
    match tracer.intersect(to_vec(c), to_vec((p - c) / dist)) {
        Some(hit) => f64::from(hit.t) > dist * (1.0 - 1e-3) - 1e-3,
        None => true,
    }
}

/// Mean absolute difference (gray levels) between every pair of cameras
/// over the panorama pixels both see (inside the image and not occluded),
/// with the pixels warped at inverse depth `warp_inv`, and the number of
/// such pixel pairs.
fn pairwise_mad(
    tracer: &Tracer,
    rig: &omnimvs_camera::Rig,
    images: &[GrayImage],
    grid: &EquirectGrid,
    gt: &[f32],
    warp_inv: &[f32],
) -> (f64, usize) {
    let warped: Vec<_> = rig
        .cameras
        .iter()
        .zip(images)
        .map(|(c, img)| {
            warp_camera_to_panorama(c, grid, img, None, InvDepthSource::Map(warp_inv)).unwrap()
        })
        .collect();
    let vis: Vec<Vec<bool>> = rig
        .cameras
        .iter()
        .map(|c| {
            (0..grid.len())
                .map(|k| visible(tracer, c, grid, gt, k))
                .collect()
        })
        .collect();
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 0..warped.len() {
        for j in i + 1..warped.len() {
            for k in 0..grid.len() {
                if warped[i].1[k] && warped[j].1[k] && vis[i][k] && vis[j][k] {
                    sum += f64::from((warped[i].0[k] - warped[j].0[k]).abs());
                    n += 1;
                }
            }
        }
    }
    (sum / n.max(1) as f64, n)
}

fn check(kind: SceneKind, want_room: bool) {
    check_rig(kind, want_room, preset_rig().unwrap(), (192, 200), 2.0);
}

/// [`check`] for `source` rendered at `size` (height, width): a wrong depth must disagree
/// `wrong_ratio` times more than the ground truth (less for a rig of short baselines, whose
/// views shift less with depth).
fn check_rig(
    kind: SceneKind,
    want_room: bool,
    source: omnimvs_synth::rig::RigSource,
    size: (u32, u32),
    wrong_ratio: f64,
) {
    let rig = resize_rig(&source.rig, size.0, size.1).unwrap();
    let params = GenParams::new(source.min_depth_m, rig_radius_m(&rig));
    // The first frame of the wanted background (room or sky).
    let scene = (1..50)
        .map(|f| generate(kind, 11, f, &params).unwrap())
        .find(|s| {
            kind == SceneKind::House || (matches!(s.objects[0].shape, ShapeSpec::Box) == want_room)
        })
        .unwrap();
    let tracer = Tracer::new(&scene, &[]).unwrap();
    let images: Vec<GrayImage> = render_gray_frame(&tracer, &rig, 4);
    assert_eq!(images.len(), rig.len());
    let grid = EquirectGrid::new(160, 320, 90.0).unwrap();
    let gt = render_inverse_depth(&tracer, &grid);
    let (good, n) = pairwise_mad(&tracer, &rig, &images, &grid, &gt, &gt);
    let half: Vec<f32> = gt.iter().map(|v| v * 0.5).collect();
    let (bad_half, _) = pairwise_mad(&tracer, &rig, &images, &grid, &gt, &half);
    let double: Vec<f32> = gt.iter().map(|v| v * 2.0).collect();
    let (bad_double, _) = pairwise_mad(&tracer, &rig, &images, &grid, &gt, &double);
    println!(
        "{} (room: {want_room}, frame {}): MAD with GT {good:.2} gray levels over {n} overlapping pixel pairs; \
         half inverse depth {bad_half:.2}; double {bad_double:.2}",
        kind.name(),
        scene.frame
    );
    assert!(n > 10_000, "cameras barely overlap: {n}");
    assert!(
        good < 6.0,
        "cameras disagree through the ground truth: MAD {good:.2}"
    );
    assert!(
        bad_half > wrong_ratio * good && bad_double > wrong_ratio * good,
        "a wrong depth agrees as well: {bad_half:.2}, {bad_double:.2} vs {good:.2}"
    );
}

#[test]
fn things_in_a_room_are_consistent_across_cameras() {
    check(SceneKind::Things, true);
}

#[test]
fn things_under_a_sky_are_consistent_across_cameras() {
    check(SceneKind::Things, false);
}

#[test]
fn house_is_consistent_across_cameras() {
    check(SceneKind::House, true);
}

/// A bundled example rig file, read as `omnimvs synth --rig` reads it.
fn example_rig(name: &str) -> omnimvs_synth::rig::RigSource {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/rigs")
        .join(name);
    omnimvs_synth::rig::load_rig_with(
        path.to_str().unwrap(),
        None,
        omnimvs_camera::FrameChoice::Fitted,
    )
    .unwrap()
}

#[test]
fn a_compact_double_sphere_rig_is_consistent_across_cameras() {
    // Four cameras 5 to 7 cm apart (Basalt calibration.json).
    let source = example_rig("ds-4cam-compact/calibration.json");
    check_rig(SceneKind::Things, true, source, (304, 304), 1.3);
}

#[test]
fn a_six_camera_kannala_brandt_rig_is_consistent_across_cameras() {
    // Six 240-degree cameras (config.yaml, model kb4).
    let source = example_rig("kb4-6cam-240/config.yaml");
    assert_eq!(source.rig.len(), 6);
    check_rig(SceneKind::House, true, source, (200, 200), 2.0);
}

#[test]
fn a_three_camera_extended_unified_rig_is_consistent_across_cameras() {
    // Three cameras (Kalibr camchain.yaml, in the fitted frame).
    let source = example_rig("eucm-3cam/camchain.yaml");
    assert_eq!(source.rig.len(), 3);
    check_rig(SceneKind::Things, true, source, (400, 400), 2.0);
}

#[test]
fn random_rigs_of_every_lens_model_are_consistent_across_cameras() {
    // The first random rig of each lens model (their images rendered with the true rig).
    let spec = omnimvs_synth::random_rig::RandomRigSpec::default();
    let mut seen = std::collections::BTreeSet::new();
    for seed in 0..100 {
        let source = omnimvs_synth::random_rig::random_rig(seed, &spec).unwrap();
        let model = source.rig.cameras[0].model.name();
        if source.rig.len() > 5 || !seen.insert(model) {
            continue;
        }
        println!("random:{seed}: {} cameras of {model}", source.rig.len());
        check_rig(SceneKind::Things, true, source.into(), (256, 256), 1.3);
    }
    assert_eq!(seen.len(), 4, "{seen:?}");
}
