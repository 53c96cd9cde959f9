//! Scenes for the classical method's tests and benchmarks, made by
//! `omnimvs-synth` (the workspace's one renderer): the published rig at a
//! chosen size, a noise-textured sphere centred on the rig, generated rooms.
#![allow(dead_code, clippy::expect_used)] // each user takes what it needs; fixtures

use omnimvs_camera::Rig;
use omnimvs_core::GrayImage;
use omnimvs_data::gt::InvDepthMap;
use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::rig::{preset_rig, resize_rig, rig_radius_m};
use omnimvs_synth::texture::{Pattern, TextureSpec};
use omnimvs_synth::{
    GenParams, ObjectSpec, Placement, SceneKind, SceneSpec, ShapeSpec, Tracer, generate,
    render_gray_frame, render_inverse_depth_map,
};

/// Samples per pixel of the rendered images (anti-aliasing).
const SPP: u32 = 4;

/// The published 4-camera rig with images of `768 x 800` pixels times `scale`
/// (the intrinsics rescaled with them).
pub fn published_rig(scale: f64) -> Rig {
    let rig = preset_rig().expect("the embedded preset").rig;
    let height = (768.0 * scale).round() as u32;
    let width = (800.0 * scale).round() as u32;
    resize_rig(&rig, height, width).expect("a positive size")
}

/// A sphere of `radius_m` centred on the rig, textured with fractal noise:
/// every output pixel at the same depth (the "fronto-parallel" case of
/// spherical sweeping).
pub fn textured_sphere(radius_m: f64, seed: i32) -> SceneSpec {
    let mut scene = SceneSpec::empty();
    scene.objects.push(ObjectSpec {
        shape: ShapeSpec::Sphere,
        placement: Placement::at([0.0; 3], [radius_m; 3]),
        texture: TextureSpec {
            pattern: Pattern::Noise {
                freq: 1.0,
                octaves: 3,
                seed,
            },
            lo: 0.1,
            hi: 0.9,
            detail: 0.1,
            detail_freq: 8.0,
            detail_seed: seed.wrapping_add(1),
        },
        texture_scale_m: 0.25,
    });
    scene
}

/// An OmniThings-like scene of `seed` for `rig`: textured objects all around
/// the rig inside a room (the first frame of the seed whose background is a
/// room, not a sky, so that every pixel has a finite depth).
pub fn room(rig: &Rig, seed: u64) -> SceneSpec {
    let params = GenParams::new(omnimvs_synth::rig::PRESET_MIN_DEPTH_M, rig_radius_m(rig));
    (1..)
        .map(|frame| generate(SceneKind::Things, seed, frame, &params).expect("a things scene"))
        .find(|scene| scene.sky.is_none())
        .expect("a frame in a room")
}

/// One rendered frame of a scene: the camera images and the ground truth.
pub struct Rendered {
    pub images: Vec<GrayImage>,
    tracer: Tracer,
}

impl Rendered {
    /// Renders every camera of `rig`.
    pub fn new(scene: &SceneSpec, rig: &Rig) -> Self {
        let tracer = Tracer::new(scene, &[]).expect("a valid scene");
        let images = render_gray_frame(&tracer, rig, SPP);
        Self { images, tracer }
    }

    /// The ground-truth inverse depth (1/m) on `grid`; 0 where a ray hits nothing.
    pub fn inverse_depth(&self, grid: &EquirectGrid) -> InvDepthMap {
        render_inverse_depth_map(&self.tracer, grid)
    }
}
