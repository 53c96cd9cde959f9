//! The ground truth is exact: analytic scenes give their analytic inverse
//! depth to f32 precision.

#![allow(clippy::unwrap_used, clippy::expect_used)] // helpers of tests

use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::rig::{preset_rig, resize_rig};
use omnimvs_synth::texture::TextureSpec;
use omnimvs_synth::{
    ObjectSpec, Placement, SceneSpec, ShapeSpec, Tracer, render_fisheye, render_inverse_depth,
};

fn scene_with(objects: Vec<ObjectSpec>) -> SceneSpec {
    SceneSpec {
        objects,
        ..SceneSpec::empty()
    }
}

fn object(shape: ShapeSpec, placement: Placement) -> ObjectSpec {
    ObjectSpec {
        shape,
        placement,
        texture: TextureSpec::flat(0.8),
        texture_scale_m: 1.0,
    }
}

#[test]
fn centred_sphere_gives_one_over_r_everywhere() {
    let grid = EquirectGrid::new(320, 640, 90.0).unwrap();
    for r in [1.7f64, 5.3, 42.0] {
        let scene = scene_with(vec![object(
            ShapeSpec::Sphere,
            Placement::at([0.0; 3], [r; 3]),
        )]);
        let tracer = Tracer::new(&scene, &[]).unwrap();
        let gt = render_inverse_depth(&tracer, &grid);
        let want = (1.0 / r) as f32;
        let worst = gt
            .iter()
            .map(|&v| ((v - want) / want).abs())
            .fold(0.0f32, f32::max);
        assert!(
            worst <= 4.0 * f32::EPSILON,
            "r = {r}: worst relative error {worst:e}"
        );
    }
}

#[test]
fn floor_plane_matches_its_analytic_inverse_depth() {
    // A floor 2 m below the rig (y points down): inverse depth = d_y / 2
    // for rays going down, 0 (nothing) for the others.
    let h = 2.0;
    let scene = scene_with(vec![object(
        ShapeSpec::Rect,
        Placement::at([0.0, h, 0.0], [1e4, 1.0, 1e4]),
    )]);
    let tracer = Tracer::new(&scene, &[]).unwrap();
    let grid = EquirectGrid::new(320, 640, 90.0).unwrap();
    let gt = render_inverse_depth(&tracer, &grid);
    let mut checked = 0;
    for row in 0..grid.height {
        for col in 0..grid.width {
            let d = grid.ray(row as f64, col as f64);
            let got = f64::from(gt[row * grid.width + col]);
            if d.y > 1e-3 {
                let want = d.y / h;
                assert!(
                    ((got - want) / want).abs() < 2e-6,
                    "({row},{col}): {got} vs {want}"
                );
                checked += 1;
            } else if d.y < -1e-3 {
                assert_eq!(got, 0.0);
            }
        }
    }
    assert!(checked > 90_000);
}

#[test]
fn fisheye_is_black_outside_the_fov_and_lit_inside() {
    let rig = resize_rig(&preset_rig().unwrap().rig, 96, 100).unwrap();
    let scene = scene_with(vec![object(
        ShapeSpec::Sphere,
        Placement::at([0.0; 3], [6.0; 3]),
    )]);
    let tracer = Tracer::new(&scene, &[]).unwrap();
    for cam in &rig.cameras {
        let img = render_fisheye(&tracer, cam, 1);
        let (w, h) = (cam.model.width() as usize, cam.model.height() as usize);
        for row in 0..h {
            for col in 0..w {
                let inside = cam
                    .model
                    .unproject(omnimvs_camera::Pixel::new(col as f64, row as f64))
                    .is_some();
                let v = img[row * w + col];
                if inside {
                    assert!(
                        v > 0,
                        "camera {} pixel ({col},{row}) inside the FOV is black",
                        cam.id
                    );
                } else {
                    assert_eq!(
                        v, 0,
                        "camera {} pixel ({col},{row}) outside the FOV is lit",
                        cam.id
                    );
                }
            }
        }
    }
}
