//! What the scene generators share: parameters, bounding-box clearance,
//! random skies and lights.

use nalgebra::{Matrix3, Point3, Vector3};

use crate::Difficulty;
use crate::rng::Rng;
use crate::scene::{LightSpec, Placement, SkySpec};

/// Parameters of the scene generators.
#[derive(Debug, Clone, PartialEq)]
pub struct GenParams {
    /// The rig's minimum depth (`omnimvs_sweep_min_depth`), metres: no
    /// geometry is placed closer to the rig origin.
    pub min_depth_m: f64,
    /// Largest distance of a camera centre from the rig origin, metres.
    pub rig_radius_m: f64,
    /// Objects per `things` scene (64 in OmniThings).
    pub num_objects: usize,
    /// User mesh files (OBJ/PLY) that `things` scenes may use.
    pub meshes: Vec<String>,
    /// How hard the scenes are (textures, shapes, lighting).
    pub difficulty: Difficulty,
}

impl GenParams {
    /// The published rig's values and 64 objects.
    pub fn new(min_depth_m: f64, rig_radius_m: f64) -> Self {
        Self {
            min_depth_m,
            rig_radius_m,
            num_objects: 64,
            meshes: Vec::new(),
            difficulty: Difficulty::Standard,
        }
    }

    /// The least distance (metres) from the rig origin to any geometry: the
    /// minimum depth, and never less than 0.25 m beyond the cameras.
    pub fn clearance_m(&self) -> f64 {
        self.min_depth_m.max(self.rig_radius_m + 0.25)
    }
}

/// Distance from `point` to the axis-aligned bounding box of an object's
/// unit cube `[-1, 1]^3` under `placement` (0 when inside). Every shape lies
/// inside its unit cube, so this is a lower bound of the distance to the
/// object.
pub fn aabb_distance(placement: &Placement, point: &Vector3<f64>) -> f64 {
    let lin: Matrix3<f64> =
        placement.rotation_matrix() * Matrix3::from_diagonal(&Vector3::from(placement.scale));
    let half = Vector3::from_fn(|r, _| lin.row(r).abs().sum());
    let c = Vector3::from(placement.translation_m);
    let lo = c - half;
    let hi = c + half;
    let q = Point3::from(point.sup(&lo).inf(&hi));
    (q.coords - point).norm()
}

/// A random sky: gradient, clouds, sun.
pub fn random_sky(rng: &mut Rng) -> SkySpec {
    let horizon = rng.range(0.55, 0.9) as f32;
    let elevation = rng.range(0.15, 1.2);
    let azimuth = rng.range(0.0, std::f64::consts::TAU);
    SkySpec {
        zenith: (horizon - rng.range(0.1, 0.4) as f32).max(0.1),
        horizon,
        ground: rng.range(0.15, 0.4) as f32,
        cloud_cover: rng.range(0.1, 0.8) as f32,
        cloud_brightness: rng.range(0.7, 1.0) as f32,
        cloud_freq: rng.log_range(1.5, 6.0) as f32,
        cloud_seed: rng.seed_i32(),
        sun_dir: [
            (elevation.cos() * azimuth.cos()) as f32,
            -elevation.sin() as f32,
            (elevation.cos() * azimuth.sin()) as f32,
        ],
        sun_strength: rng.range(0.0, 0.6) as f32,
    }
}

/// A light: the sun of the sky when there is one, else a point light inside
/// the room (`(placement, half extents)`), else above the rig.
pub fn random_light(
    rng: &mut Rng,
    sky: Option<&SkySpec>,
    room: Option<(&Placement, Vector3<f64>)>,
) -> LightSpec {
    let ambient = rng.range(0.25, 0.5) as f32;
    let diffuse = rng.range(0.5, 0.8) as f32;
    if let Some(s) = sky {
        return LightSpec {
            position_m: s.sun_dir.map(f64::from),
            directional: true,
            ambient,
            diffuse,
            range_m: None,
        };
    }
    let position = match room {
        Some((placement, half)) => {
            let local = Vector3::new(
                rng.range(-0.8, 0.8) * half.x,
                rng.range(-0.95, -0.6) * half.y,
                rng.range(-0.8, 0.8) * half.z,
            );
            placement.isometry() * Point3::from(local)
        }
        None => Point3::new(0.0, -5.0, 0.0),
    };
    LightSpec {
        position_m: position.coords.into(),
        directional: false,
        ambient,
        diffuse,
        range_m: None,
    }
}

/// The lights of a `hard` scene: darker (little ambient light) and uneven:
/// the main light ([`random_light`]'s position) and 1-3 more point lights,
/// every point light with a strong falloff (range 0.2-1.2 times the room's
/// mean half extent, or 5 m under a sky). In a room
/// (`(placement, half extents)`) the extra lights are anywhere inside it;
/// under a sky the sun stays and 0-2 point lights hang among the objects,
/// `near_m..far_m` from the rig.
pub fn random_hard_lights(
    rng: &mut Rng,
    sky: Option<&SkySpec>,
    room: Option<(&Placement, Vector3<f64>)>,
    near_m: f64,
    far_m: f64,
) -> (LightSpec, Vec<LightSpec>) {
    // Falloff distances follow the room's size, so a large room is dim far
    // from its lights rather than black.
    let size_m = room.map_or(5.0, |(_, half)| half.mean());
    let mut main = random_light(rng, sky, room);
    main.ambient = rng.range(0.06, 0.2) as f32;
    main.diffuse = rng.range(0.7, 1.4) as f32;
    if !main.directional {
        main.range_m = Some(size_m * rng.log_range(0.4, 1.2));
    }
    let count = if sky.is_some() {
        rng.below(3)
    } else {
        1 + rng.below(3)
    };
    let extra = (0..count)
        .map(|_| {
            let position = match room {
                Some((placement, half)) => {
                    let local = Vector3::new(
                        rng.range(-0.9, 0.9) * half.x,
                        rng.range(-0.9, 0.9) * half.y,
                        rng.range(-0.9, 0.9) * half.z,
                    );
                    placement.isometry() * Point3::from(local)
                }
                None => Point3::from(rng.marsaglia() * rng.range(near_m, far_m.max(near_m))),
            };
            LightSpec {
                position_m: position.coords.into(),
                directional: false,
                ambient: 0.0,
                diffuse: rng.range(0.3, 1.2) as f32,
                range_m: Some(size_m * rng.log_range(0.2, 1.0)),
            }
        })
        .collect();
    (main, extra)
}
