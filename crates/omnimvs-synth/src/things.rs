//! OmniThings-like scenes: random objects all around the rig (directions by
//! Marsaglia's method), in a cuboid room or under a sky.

use nalgebra::{UnitQuaternion, Vector3};

use crate::rng::Rng;
use crate::scene::{ObjectSpec, Placement, SceneKind, SceneSpec, ShapeSpec, generator_name};
use crate::shared::{GenParams, aabb_distance, random_hard_lights, random_light, random_sky};
use crate::texture::TextureSpec;

/// Chance that the background is a room rather than a sky.
const ROOM_PROBABILITY: f64 = 0.5;
/// Farthest object centre under a sky, metres.
const SKY_MAX_DISTANCE_M: f64 = 40.0;
/// Angular radius range of an object seen from the rig, radians.
const ANGULAR_RADIUS: (f64, f64) = (0.08, 0.6);

/// A cuboid room around the rig: half extents, yaw, centre.
struct Room {
    half: Vector3<f64>,
    placement: Placement,
}

impl Room {
    /// Distance from the rig origin to the room's wall along unit `dir`.
    fn exit_distance(&self, dir: &Vector3<f64>) -> f64 {
        let iso = self.placement.isometry();
        let o = iso
            .inverse_transform_point(&nalgebra::Point3::origin())
            .coords;
        let d = iso.inverse_transform_vector(dir);
        (0..3)
            .map(|k| {
                if d[k].abs() < 1e-12 {
                    f64::INFINITY
                } else {
                    let wall = self.half[k] * d[k].signum();
                    (wall - o[k]) / d[k]
                }
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// Generates the `things` scene of `(seed, frame)`.
pub fn generate(seed: u64, frame: u32, params: &GenParams) -> SceneSpec {
    let mut rng = Rng::for_frame(seed, "things", frame);
    let hard = params.difficulty.is_hard();
    let texture = |rng: &mut Rng| {
        if hard {
            TextureSpec::random_hard(rng, 1.0)
        } else {
            TextureSpec::random(rng, 1.0)
        }
    };
    let clearance = params.clearance_m();
    let mut objects = Vec::with_capacity(params.num_objects + 1);

    let room = if rng.chance(ROOM_PROBABILITY) {
        let min_half = 1.6 * clearance + 1.0;
        let half = Vector3::new(
            rng.log_range(min_half, min_half.max(4.0) * 5.0),
            rng.log_range(min_half, min_half.max(3.0) * 2.5),
            rng.log_range(min_half, min_half.max(4.0) * 5.0),
        );
        // The rig anywhere that keeps the walls beyond the clearance.
        let free = half.map(|h| (h - clearance * 1.2).max(0.0));
        let centre = Vector3::new(
            rng.range(-free.x, free.x),
            rng.range(-free.y, free.y),
            rng.range(-free.z, free.z),
        );
        let yaw = UnitQuaternion::from_axis_angle(
            &Vector3::y_axis(),
            rng.range(0.0, std::f64::consts::TAU),
        );
        let placement = Placement::new(&yaw, yaw * centre, half.into());
        let texture = texture(&mut rng);
        objects.push(ObjectSpec {
            shape: ShapeSpec::Box,
            placement,
            texture,
            texture_scale_m: rng.log_range(0.5, 4.0),
        });
        Some(Room { half, placement })
    } else {
        None
    };
    let sky = if room.is_none() {
        Some(random_sky(&mut rng))
    } else {
        None
    };

    for _ in 0..params.num_objects {
        let dir = rng.marsaglia();
        let far = match &room {
            Some(r) => (r.exit_distance(&dir) * 0.9).max(clearance * 1.1),
            None => SKY_MAX_DISTANCE_M.max(clearance * 2.0),
        };
        // Uniform in inverse depth, as the sweep samples it.
        let inv = rng.range(1.0 / far, 1.0 / clearance);
        let mut dist = 1.0 / inv;
        let radius = dist * rng.log_range(ANGULAR_RADIUS.0, ANGULAR_RADIUS.1).tan();
        let rotation = rng.rotation();
        let (shape, thin_aspect) = if hard {
            random_shape_hard(&mut rng, params.meshes.len())
        } else {
            (random_shape(&mut rng, params.meshes.len()), None)
        };
        let mut aspect = [
            rng.range(0.35, 1.0),
            rng.range(0.35, 1.0),
            rng.range(0.35, 1.0),
        ];
        let m = aspect.iter().copied().fold(0.0, f64::max);
        aspect.iter_mut().for_each(|a| *a /= m);
        if matches!(shape, ShapeSpec::Sphere) && rng.chance(0.5) {
            aspect = [1.0; 3];
        }
        if let Some(a) = thin_aspect {
            aspect = a;
        }
        let scale = aspect.map(|a| a * radius);
        let texture = texture(&mut rng);
        let texture_scale_m = radius * rng.range(0.3, 1.5);
        // Keep the bounding box beyond the clearance: push outwards.
        let mut placement = Placement::new(&rotation, dir * dist, scale);
        for _ in 0..64 {
            let gap = aabb_distance(&placement, &Vector3::zeros());
            if gap >= clearance {
                break;
            }
            dist += clearance - gap + 0.01;
            placement = Placement::new(&rotation, dir * dist, scale);
        }
        objects.push(ObjectSpec {
            shape,
            placement,
            texture,
            texture_scale_m,
        });
    }

    let room_box = room.as_ref().map(|r| (&r.placement, r.half));
    let (light, extra_lights) = if hard {
        random_hard_lights(&mut rng, sky.as_ref(), room_box, clearance, 15.0)
    } else {
        (random_light(&mut rng, sky.as_ref(), room_box), Vec::new())
    };
    SceneSpec {
        generator: generator_name(),
        kind: SceneKind::Things,
        seed,
        frame,
        world_from_rig: Placement::identity(),
        objects,
        sky,
        light,
        meshes: params.meshes.clone(),
        extra_lights,
        camera_effects: Vec::new(),
    }
}

fn random_shape(rng: &mut Rng, num_user_meshes: usize) -> ShapeSpec {
    if num_user_meshes > 0 && rng.chance(0.4) {
        return ShapeSpec::UserMesh {
            index: rng.below(num_user_meshes),
        };
    }
    match rng.below(20) {
        0..=2 => ShapeSpec::Sphere,
        3..=5 => ShapeSpec::Box,
        6..=7 => ShapeSpec::Cylinder { segments: 32 },
        8..=9 => ShapeSpec::Cone { segments: 32 },
        10..=11 => ShapeSpec::Torus {
            minor: rng.range(0.12, 0.4) as f32,
            major_segments: 32,
            minor_segments: 16,
        },
        12..=15 => ShapeSpec::Blob {
            seed: rng.seed_i32(),
            amplitude: rng.range(0.2, 0.6) as f32,
            frequency: rng.range(0.8, 2.5) as f32,
            subdivisions: 3,
        },
        _ => ShapeSpec::Extrusion {
            seed: rng.next_u64(),
            corners: 3 + rng.below(10) as u32,
            layers: 1 + rng.below(6) as u32,
            twist: rng.range(-2.0, 2.0) as f32,
            taper: rng.range(0.3, 1.3) as f32,
        },
    }
}

/// A shape of a `hard` scene, and the aspect (unit-space scale per axis,
/// largest 1) that makes it thin, when it must be: 35% the shapes of
/// [`random_shape`], the rest thin or concave like many ShapeNet models:
/// rods, plates, rings, frames and plates with holes, lattices, tubes.
fn random_shape_hard(rng: &mut Rng, num_user_meshes: usize) -> (ShapeSpec, Option<[f64; 3]>) {
    let roll = rng.f64();
    if roll < 0.35 {
        return (random_shape(rng, num_user_meshes), None);
    }
    if roll < 0.47 {
        // A rod: a thin cylinder or square bar.
        let w = rng.log_range(0.015, 0.08);
        let shape = if rng.chance(0.5) {
            ShapeSpec::Cylinder { segments: 16 }
        } else {
            ShapeSpec::Box
        };
        return (shape, Some([w, 1.0, w * rng.range(0.7, 1.0)]));
    }
    if roll < 0.59 {
        // A plate or board.
        return (
            ShapeSpec::Box,
            Some([1.0, rng.log_range(0.01, 0.05), rng.range(0.3, 1.0)]),
        );
    }
    if roll < 0.69 {
        // A ring.
        return (
            ShapeSpec::Torus {
                minor: rng.log_range(0.03, 0.15) as f32,
                major_segments: 48,
                minor_segments: 8,
            },
            Some([1.0, 1.0, rng.range(0.6, 1.0)]),
        );
    }
    if roll < 0.81 {
        // A frame or a plate with holes.
        let cells = 1 + rng.below(4) as u32;
        return (
            ShapeSpec::Grid {
                cells_x: cells,
                cells_z: (cells + rng.below(3) as u32).saturating_sub(1).max(1),
                bar: rng.log_range(0.04, 0.2) as f32,
                half_y: rng.log_range(0.01, 0.06) as f32,
            },
            Some([1.0, 1.0, rng.range(0.5, 1.0)]),
        );
    }
    if roll < 0.89 {
        return (
            ShapeSpec::Lattice {
                cells: 1 + rng.below(3) as u32,
                bar: rng.log_range(0.03, 0.1) as f32,
            },
            None,
        );
    }
    // A pipe or bucket: seen from an end, concave.
    (
        ShapeSpec::Tube {
            segments: 32,
            inner: rng.range(0.75, 0.95) as f32,
        },
        Some([1.0, rng.range(0.4, 1.0), 1.0]),
    )
}
