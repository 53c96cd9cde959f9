//! OmniHouse-like scenes: a house of rectangular rooms on a grid, walls with
//! doorways and windows, floors, ceilings, furniture-like objects, large
//! low-texture surfaces, a ground and a sky outside; the rig at a random
//! position and orientation inside one room.
//!
//! The scene frame has y down (as the rig frame); the floor is `y = 0`.

use nalgebra::{UnitQuaternion, Vector3};

use crate::rng::Rng;
use crate::scene::{
    LightSpec, ObjectSpec, Placement, SceneKind, SceneSpec, ShapeSpec, generator_name,
};
use crate::shared::{GenParams, aabb_distance, random_sky};
use crate::texture::{Pattern, TextureSpec};

const WALL_THICKNESS_M: f64 = 0.12;

/// Builder of one scene: the objects so far and the shared textures.
struct House {
    objects: Vec<ObjectSpec>,
    wall_textures: Vec<TextureSpec>,
}

fn obj(
    shape: ShapeSpec,
    placement: Placement,
    texture: TextureSpec,
    texture_scale_m: f64,
) -> ObjectSpec {
    ObjectSpec {
        shape,
        placement,
        texture,
        texture_scale_m,
    }
}

/// An axis-aligned box from its corners (world frame).
fn aabox(lo: [f64; 3], hi: [f64; 3], texture: TextureSpec, texture_scale_m: f64) -> ObjectSpec {
    let c = [0, 1, 2].map(|k| (lo[k] + hi[k]) / 2.0);
    let h = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / 2.0).abs().max(1e-3));
    obj(
        ShapeSpec::Box,
        Placement::at(c, h),
        texture,
        texture_scale_m,
    )
}

fn low_texture(rng: &mut Rng) -> TextureSpec {
    if rng.chance(0.5) {
        let mut t = TextureSpec::flat(rng.range(0.45, 0.9) as f32);
        t.detail = rng.range(0.0, 0.03) as f32;
        t.detail_freq = rng.log_range(2.0, 10.0) as f32;
        t.detail_seed = rng.seed_i32();
        t
    } else {
        let richness = rng.range(0.1, 0.35);
        TextureSpec::random(rng, richness)
    }
}

fn floor_texture(rng: &mut Rng) -> TextureSpec {
    let mid = rng.range(0.25, 0.7) as f32;
    let contrast = rng.range(0.1, 0.5) as f32;
    let pattern = match rng.below(4) {
        0 => Pattern::Checker {
            freq: rng.range(1.0, 3.0) as f32,
        },
        1 => Pattern::Marble {
            freq: rng.range(3.0, 8.0) as f32,
            axis: [1.0, 0.0, 0.0],
            turbulence: rng.range(0.2, 1.0) as f32,
            seed: rng.seed_i32(),
        },
        2 => Pattern::Stripes {
            freq: rng.range(3.0, 7.0) as f32,
            axis: if rng.chance(0.5) {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 0.0, 1.0]
            },
            duty: 0.95,
            soft: 0.02,
        },
        _ => Pattern::Noise {
            freq: rng.range(2.0, 8.0) as f32,
            octaves: 4,
            seed: rng.seed_i32(),
        },
    };
    let floor = TextureSpec::banded(pattern, mid, contrast, [0.02, 0.98]);
    floor.with_random_detail(rng, [0.0, 0.1], [6.0, 20.0])
}

/// One piece of furniture in its own frame: floor at `y = 0`, y down,
/// centred on the origin in x and z.
enum Part {
    /// Box from `lo` to `hi`.
    Box([f64; 3], [f64; 3]),
    /// Vertical cylinder: centre (x, z), radius, from height `y0` up to `y1`
    /// (heights above the floor, positive).
    Cylinder(f64, f64, f64, f64, f64),
    /// Cone with apex at height `y1`, base of radius r at `y0`.
    Cone(f64, f64, f64, f64, f64),
    /// Sphere: centre (x, height, z), radius.
    Sphere(f64, f64, f64, f64),
    /// Blob: centre (x, height, z), radius.
    Blob(f64, f64, f64, f64, i32),
}

/// A piece of furniture: parts, texture per part (index into `textures`),
/// footprint half extents (x, z).
struct Item {
    parts: Vec<(Part, usize)>,
    textures: Vec<TextureSpec>,
    footprint: (f64, f64),
}

fn legs(w: f64, d: f64, h: f64, t: f64, tex: usize) -> Vec<(Part, usize)> {
    let (x, z) = (w / 2.0 - t, d / 2.0 - t);
    [(-x, -z), (x, -z), (-x, z), (x, z)]
        .into_iter()
        .map(|(cx, cz)| {
            (
                Part::Box(
                    [cx - t / 2.0, -h, cz - t / 2.0],
                    [cx + t / 2.0, 0.0, cz + t / 2.0],
                ),
                tex,
            )
        })
        .collect()
}

/// A random piece of furniture (or a person, a plant, a rug) with two random textures: part
/// textures index 0 (wood) and 1 (fabric).
fn random_item(rng: &mut Rng) -> Item {
    let (r1, r2) = (rng.range(0.5, 1.0), rng.range(0.3, 1.0));
    let wood = TextureSpec::random(rng, r1);
    let fabric = TextureSpec::random(rng, r2);
    let textures = vec![wood, fabric];
    let mut parts = Vec::new();
    let footprint = match rng.below(11) {
        0 => table(rng, &mut parts),
        1 => chair(rng, &mut parts),
        2 => bed(rng, &mut parts),
        3 => sofa(rng, &mut parts),
        4 => cabinet(rng, &mut parts),
        5 => round_table(rng, &mut parts),
        6 => floor_lamp(rng, &mut parts),
        7 => person(rng, &mut parts),
        8 => tv_on_stand(rng, &mut parts),
        9 => plant(rng, &mut parts),
        _ => rug(rng, &mut parts),
    };
    Item {
        parts,
        textures,
        footprint,
    }
}

/// Table: its parts pushed onto `parts`, its footprint's half extents returned.
fn table(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let (w, d, h) = (
        rng.range(0.8, 1.8),
        rng.range(0.6, 1.0),
        rng.range(0.7, 0.78),
    );
    parts.push((
        Part::Box([-w / 2.0, -h, -d / 2.0], [w / 2.0, -h + 0.04, d / 2.0]),
        0,
    ));
    parts.extend(legs(w, d, h - 0.04, 0.05, 0));
    (w / 2.0, d / 2.0)
}

/// Chair: its parts pushed onto `parts`, its footprint's half extents returned.
fn chair(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let (w, h) = (rng.range(0.4, 0.5), rng.range(0.42, 0.48));
    parts.push((
        Part::Box([-w / 2.0, -h, -w / 2.0], [w / 2.0, -h + 0.05, w / 2.0]),
        1,
    ));
    parts.push((
        Part::Box([-w / 2.0, -h - 0.5, w / 2.0 - 0.05], [w / 2.0, -h, w / 2.0]),
        0,
    ));
    parts.extend(legs(w, w, h, 0.04, 0));
    (w / 2.0, w / 2.0)
}

/// Bed: its parts pushed onto `parts`, its footprint's half extents returned.
fn bed(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let (w, l) = (rng.range(1.0, 1.8), rng.range(1.9, 2.1));
    parts.push((
        Part::Box([-w / 2.0, -0.5, -l / 2.0], [w / 2.0, 0.0, l / 2.0]),
        1,
    ));
    parts.push((
        Part::Box([-w / 2.0, -1.0, l / 2.0 - 0.06], [w / 2.0, 0.0, l / 2.0]),
        0,
    ));
    parts.push((
        Part::Box(
            [-w / 2.0 + 0.1, -0.62, l / 2.0 - 0.5],
            [w / 2.0 - 0.1, -0.5, l / 2.0 - 0.1],
        ),
        1,
    ));
    (w / 2.0, l / 2.0)
}

/// Sofa: its parts pushed onto `parts`, its footprint's half extents returned.
fn sofa(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let (w, d) = (rng.range(1.5, 2.3), rng.range(0.8, 0.95));
    parts.push((
        Part::Box([-w / 2.0, -0.42, -d / 2.0], [w / 2.0, 0.0, d / 2.0]),
        1,
    ));
    parts.push((
        Part::Box([-w / 2.0, -0.85, d / 2.0 - 0.2], [w / 2.0, -0.42, d / 2.0]),
        1,
    ));
    for s in [-1.0, 1.0] {
        let x0 = s * (w / 2.0 - 0.1);
        parts.push((
            Part::Box([x0 - 0.1, -0.62, -d / 2.0], [x0 + 0.1, -0.42, d / 2.0]),
            1,
        ));
    }
    (w / 2.0, d / 2.0)
}

/// Cabinet or bookshelf: its parts pushed onto `parts`, its footprint's half extents returned.
fn cabinet(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let (w, d, h) = (
        rng.range(0.5, 1.4),
        rng.range(0.3, 0.6),
        rng.range(0.7, 2.1),
    );
    parts.push((
        Part::Box([-w / 2.0, -h, -d / 2.0], [w / 2.0, 0.0, d / 2.0]),
        0,
    ));
    (w / 2.0, d / 2.0)
}

/// Round table: its parts pushed onto `parts`, its footprint's half extents returned.
fn round_table(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let (r, h) = (rng.range(0.35, 0.65), rng.range(0.7, 0.76));
    parts.push((Part::Cylinder(0.0, 0.0, r, h - 0.04, h), 0));
    parts.push((Part::Cylinder(0.0, 0.0, 0.05, 0.0, h - 0.04), 0));
    parts.push((Part::Cylinder(0.0, 0.0, r * 0.5, 0.0, 0.03), 0));
    (r, r)
}

/// Floor lamp: its parts pushed onto `parts`, its footprint's half extents returned.
fn floor_lamp(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let h = rng.range(1.4, 1.8);
    parts.push((Part::Cylinder(0.0, 0.0, 0.15, 0.0, 0.03), 0));
    parts.push((Part::Cylinder(0.0, 0.0, 0.015, 0.03, h - 0.2), 0));
    parts.push((Part::Cone(0.0, 0.0, 0.22, h - 0.3, h), 1));
    (0.22, 0.22)
}

/// A person, roughly: its parts pushed onto `parts`, its footprint's half extents returned.
fn person(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let h = rng.range(1.55, 1.9);
    parts.push((
        Part::Box([-0.17, -0.85 * h / 1.75, -0.1], [0.17, 0.0, 0.1]),
        1,
    ));
    parts.push((
        Part::Cylinder(0.0, 0.0, 0.2, 0.85 * h / 1.75, 1.45 * h / 1.75),
        1,
    ));
    parts.push((Part::Sphere(0.0, 1.6 * h / 1.75, 0.0, 0.11), 0));
    (0.25, 0.25)
}

/// TV on a stand: its parts pushed onto `parts`, its footprint's half extents returned.
fn tv_on_stand(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let w = rng.range(0.9, 1.6);
    parts.push((
        Part::Box([-w / 2.0 - 0.1, -0.5, -0.22], [w / 2.0 + 0.1, 0.0, 0.22]),
        0,
    ));
    parts.push((
        Part::Box([-w / 2.0, -0.5 - w * 0.58, -0.03], [w / 2.0, -0.5, 0.03]),
        1,
    ));
    (w / 2.0 + 0.1, 0.22)
}

/// Plant: its parts pushed onto `parts`, its footprint's half extents returned.
fn plant(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let r = rng.range(0.15, 0.3);
    parts.push((Part::Cylinder(0.0, 0.0, r, 0.0, 2.0 * r), 0));
    parts.push((
        Part::Blob(0.0, 2.0 * r + 1.5 * r, 0.0, 1.8 * r, rng.seed_i32()),
        1,
    ));
    (1.8 * r, 1.8 * r)
}

/// Rug: its parts pushed onto `parts`, its footprint's half extents returned.
fn rug(rng: &mut Rng, parts: &mut Vec<(Part, usize)>) -> (f64, f64) {
    let (w, d) = (rng.range(1.0, 2.5), rng.range(0.8, 2.0));
    parts.push((
        Part::Box([-w / 2.0, -0.012, -d / 2.0], [w / 2.0, 0.0, d / 2.0]),
        1,
    ));
    (w / 2.0, d / 2.0)
}

/// The objects of an item placed at `(x, z)` on the floor, turned by `yaw`.
fn place_item(item: &Item, x: f64, z: f64, yaw: f64) -> Vec<ObjectSpec> {
    let rot = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), yaw);
    let at = |local: Vector3<f64>| rot * local + Vector3::new(x, 0.0, z);
    item.parts
        .iter()
        .map(|(part, tex)| {
            let texture = item.textures[*tex].clone();
            let (shape, placement) = match *part {
                Part::Box(lo, hi) => {
                    let c = Vector3::new(
                        (lo[0] + hi[0]) / 2.0,
                        (lo[1] + hi[1]) / 2.0,
                        (lo[2] + hi[2]) / 2.0,
                    );
                    let h = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / 2.0).abs().max(1e-3));
                    (ShapeSpec::Box, Placement::new(&rot, at(c), h))
                }
                Part::Cylinder(cx, cz, r, y0, y1) => (
                    ShapeSpec::Cylinder { segments: 32 },
                    Placement::new(
                        &rot,
                        at(Vector3::new(cx, -(y0 + y1) / 2.0, cz)),
                        [r, (y1 - y0) / 2.0, r],
                    ),
                ),
                Part::Cone(cx, cz, r, y0, y1) => (
                    ShapeSpec::Cone { segments: 32 },
                    Placement::new(
                        &rot,
                        at(Vector3::new(cx, -(y0 + y1) / 2.0, cz)),
                        [r, (y1 - y0) / 2.0, r],
                    ),
                ),
                Part::Sphere(cx, h, cz, r) => (
                    ShapeSpec::Sphere,
                    Placement::new(&rot, at(Vector3::new(cx, -h, cz)), [r; 3]),
                ),
                Part::Blob(cx, h, cz, r, seed) => (
                    ShapeSpec::Blob {
                        seed,
                        amplitude: 0.45,
                        frequency: 2.0,
                        subdivisions: 3,
                    },
                    Placement::new(&rot, at(Vector3::new(cx, -h, cz)), [r; 3]),
                ),
            };
            obj(shape, placement, texture, 0.7)
        })
        .collect()
}

impl House {
    fn wall_texture(&self, rng: &mut Rng) -> TextureSpec {
        self.wall_textures[rng.below(self.wall_textures.len())].clone()
    }

    /// A wall along x (`along_x`) or z at `fixed`, over `span = (s0, s1)`,
    /// full height `height`, with an optional opening
    /// `(o0, o1, bottom, top)` (heights above the floor).
    fn wall(
        &mut self,
        rng: &mut Rng,
        along_x: bool,
        fixed: f64,
        span: (f64, f64),
        height: f64,
        opening: Option<(f64, f64, f64, f64)>,
    ) {
        let (s0, s1) = span;
        let t = WALL_THICKNESS_M / 2.0;
        let texture = self.wall_texture(rng);
        let mut piece = |a0: f64, a1: f64, h0: f64, h1: f64| {
            if a1 - a0 < 1e-3 || h1 - h0 < 1e-3 {
                return;
            }
            let (lo, hi) = if along_x {
                ([a0, -h1, fixed - t], [a1, -h0, fixed + t])
            } else {
                ([fixed - t, -h1, a0], [fixed + t, -h0, a1])
            };
            self.objects.push(aabox(lo, hi, texture.clone(), 1.5));
        };
        let (s0, s1) = (s0 - t, s1 + t);
        match opening {
            None => piece(s0, s1, 0.0, height),
            Some((o0, o1, bottom, top)) => {
                piece(s0, o0, 0.0, height);
                piece(o1, s1, 0.0, height);
                piece(o0, o1, top, height);
                piece(o0, o1, 0.0, bottom);
            }
        }
    }
}

/// Generates the `house` scene of `(seed, frame)`.
pub fn generate(seed: u64, frame: u32, params: &GenParams) -> SceneSpec {
    let mut rng = Rng::for_frame(seed, "house", frame);
    let k = params.clearance_m();
    let rooms = Rooms::random(&mut rng, k);
    let mut house = House {
        objects: Vec::new(),
        wall_textures: (0..3).map(|_| low_texture(&mut rng)).collect(),
    };
    house.walls(&mut rng, &rooms);
    house.floors_and_ceilings(&mut rng, &rooms);
    house.ground(&mut rng, &rooms);
    let (ri, rj) = (rng.below(rooms.nx()), rng.below(rooms.nz()));
    let (rig_pos, world_from_rig) = place_rig(&mut rng, &rooms, (ri, rj), k);
    house.furnish(&mut rng, &rooms, &rig_pos, k);

    let sky = random_sky(&mut rng);
    let (xs, zs, height) = (&rooms.xs, &rooms.zs, rooms.height);
    let light = LightSpec {
        position_m: [
            (xs[ri] + xs[ri + 1]) / 2.0 + rng.range(-0.5, 0.5),
            -height + 0.3,
            (zs[rj] + zs[rj + 1]) / 2.0 + rng.range(-0.5, 0.5),
        ],
        directional: false,
        ambient: rng.range(0.35, 0.5) as f32,
        diffuse: rng.range(0.45, 0.65) as f32,
        range_m: None,
    };
    let (light, extra_lights) = if params.difficulty.is_hard() {
        hard_lights(&mut rng, light, xs, zs, height)
    } else {
        (light, Vec::new())
    };
    SceneSpec {
        generator: generator_name(),
        kind: SceneKind::House,
        seed,
        frame,
        world_from_rig,
        objects: house.objects,
        sky: Some(sky),
        light,
        meshes: Vec::new(),
        extra_lights,
        camera_effects: Vec::new(),
    }
}

/// The floor plan: a grid of rooms, `xs` and `zs` the walls' positions (m) along x and z,
/// every room `height` m high.
struct Rooms {
    height: f64,
    xs: Vec<f64>,
    zs: Vec<f64>,
}

impl Rooms {
    /// 1-3 by 1-3 rooms (at least two), each wide enough to hold the rig `k` m clear of its
    /// walls.
    fn random(rng: &mut Rng, k: f64) -> Self {
        let height = rng.range(2.5, 3.2).max(2.0 * k + 0.3);
        let min_w = (2.0 * k + WALL_THICKNESS_M + 0.6).max(3.0);
        let (mut nx, nz) = (1 + rng.below(3), 1 + rng.below(3));
        if nx * nz == 1 {
            nx = 2;
        }
        let mut grid = |n: usize| -> Vec<f64> {
            let mut v = vec![0.0];
            for _ in 0..n {
                let last = *v.last().unwrap_or(&0.0);
                v.push(last + rng.range(min_w, min_w + 3.5));
            }
            v
        };
        let xs = grid(nx);
        let zs = grid(nz);
        Self { height, xs, zs }
    }

    /// Rooms along x.
    fn nx(&self) -> usize {
        self.xs.len() - 1
    }

    /// Rooms along z.
    fn nz(&self) -> usize {
        self.zs.len() - 1
    }
}

/// The rig in room `(ri, rj)`, clear of walls, floor and ceiling by `k` m, turned about the
/// vertical at random and tilted by up to 8 degrees: its position and `world_from_rig`.
fn place_rig(
    rng: &mut Rng,
    rooms: &Rooms,
    (ri, rj): (usize, usize),
    k: f64,
) -> (Vector3<f64>, Placement) {
    let (xs, zs) = (&rooms.xs, &rooms.zs);
    let margin = k + WALL_THICKNESS_M / 2.0;
    let rig_pos = Vector3::new(
        rng.range(xs[ri] + margin, xs[ri + 1] - margin),
        -rng.range(k, rooms.height - k),
        rng.range(zs[rj] + margin, zs[rj + 1] - margin),
    );
    let tilt = 8f64.to_radians();
    let rotation =
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), rng.range(0.0, std::f64::consts::TAU))
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), rng.range(-tilt, tilt))
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rng.range(-tilt, tilt));
    (rig_pos, Placement::new(&rotation, rig_pos, [1.0; 3]))
}

impl House {
    /// Walls on every grid line, doorways inside, windows outside.
    fn walls(&mut self, rng: &mut Rng, rooms: &Rooms) {
        let height = rooms.height;
        for (along_x, lines, spans) in [(false, &rooms.xs, &rooms.zs), (true, &rooms.zs, &rooms.xs)]
        {
            for (i, &fixed) in lines.iter().enumerate() {
                let exterior = i == 0 || i == lines.len() - 1;
                for j in 0..spans.len() - 1 {
                    let (s0, s1) = (spans[j], spans[j + 1]);
                    let opening = if !exterior && rng.chance(0.85) {
                        let w = rng.range(0.8, 1.4).min(s1 - s0 - 0.6);
                        let o0 = rng.range(s0 + 0.3, s1 - 0.3 - w);
                        Some((o0, o0 + w, 0.0, rng.range(2.0, 2.2).min(height - 0.2)))
                    } else if exterior && rng.chance(0.5) {
                        let w = rng.range(0.8, 2.5).min(s1 - s0 - 0.6);
                        let o0 = rng.range(s0 + 0.3, s1 - 0.3 - w);
                        Some((o0, o0 + w, rng.range(0.6, 1.0), (height - 0.3).min(2.2)))
                    } else {
                        None
                    };
                    self.wall(rng, along_x, fixed, (s0, s1), height, opening);
                }
            }
        }
    }

    /// Floors and ceilings, one per room.
    fn floors_and_ceilings(&mut self, rng: &mut Rng, rooms: &Rooms) {
        let (xs, zs) = (&rooms.xs, &rooms.zs);
        for i in 0..rooms.nx() {
            for j in 0..rooms.nz() {
                let c = [(xs[i] + xs[i + 1]) / 2.0, 0.0, (zs[j] + zs[j + 1]) / 2.0];
                let h = [(xs[i + 1] - xs[i]) / 2.0, 1.0, (zs[j + 1] - zs[j]) / 2.0];
                let floor = floor_texture(rng);
                self.objects.push(obj(
                    ShapeSpec::Rect,
                    Placement::at(c, h),
                    floor,
                    rng.range(0.5, 1.5),
                ));
                let mut ceiling = TextureSpec::flat(rng.range(0.75, 0.95) as f32);
                ceiling.detail = rng.range(0.0, 0.02) as f32;
                ceiling.detail_seed = rng.seed_i32();
                self.objects.push(obj(
                    ShapeSpec::Rect,
                    Placement::at([c[0], -rooms.height, c[2]], h),
                    ceiling,
                    2.0,
                ));
            }
        }
    }

    /// The ground outside, just below the floors.
    fn ground(&mut self, rng: &mut Rng, rooms: &Rooms) {
        let (cx, cz) = (rooms.xs[rooms.nx()] / 2.0, rooms.zs[rooms.nz()] / 2.0);
        let ground = TextureSpec {
            pattern: Pattern::Noise {
                freq: rng.range(0.3, 1.0) as f32,
                octaves: 5,
                seed: rng.seed_i32(),
            },
            lo: 0.15,
            hi: rng.range(0.4, 0.6) as f32,
            detail: 0.08,
            detail_freq: 8.0,
            detail_seed: rng.seed_i32(),
        };
        self.objects.push(obj(
            ShapeSpec::Rect,
            Placement::at([cx, 0.005, cz], [80.0, 1.0, 80.0]),
            ground,
            1.0,
        ));
    }

    /// Furniture: 2-6 items per room, not overlapping, at least `k` m from the rig at
    /// `rig_pos`.
    fn furnish(&mut self, rng: &mut Rng, rooms: &Rooms, rig_pos: &Vector3<f64>, k: f64) {
        for i in 0..rooms.nx() {
            for j in 0..rooms.nz() {
                let mut footprints: Vec<(f64, f64, f64, f64)> = Vec::new();
                for _ in 0..2 + rng.below(5) {
                    let item = random_item(rng);
                    self.place_in_room(rng, rooms, (i, j), &item, &mut footprints, (rig_pos, k));
                }
            }
        }
    }

    /// Up to 20 tries to put `item` in room `(i, j)`, turned by a quarter turn and a little,
    /// against a wall half of the time, where it overlaps none of `footprints` and stays `k`
    /// m from the rig at `rig_pos`; its footprint is added when it is placed.
    fn place_in_room(
        &mut self,
        rng: &mut Rng,
        rooms: &Rooms,
        (i, j): (usize, usize),
        item: &Item,
        footprints: &mut Vec<(f64, f64, f64, f64)>,
        (rig_pos, k): (&Vector3<f64>, f64),
    ) {
        let (xs, zs) = (&rooms.xs, &rooms.zs);
        for _attempt in 0..20 {
            let quarter = rng.below(4);
            let yaw = quarter as f64 * std::f64::consts::FRAC_PI_2 + rng.range(-0.15, 0.15);
            let (fx, fz) = if quarter.is_multiple_of(2) {
                item.footprint
            } else {
                (item.footprint.1, item.footprint.0)
            };
            let (fx, fz) = (fx * 1.1 + 0.05, fz * 1.1 + 0.05);
            let lo_x = xs[i] + WALL_THICKNESS_M / 2.0 + fx;
            let hi_x = xs[i + 1] - WALL_THICKNESS_M / 2.0 - fx;
            let lo_z = zs[j] + WALL_THICKNESS_M / 2.0 + fz;
            let hi_z = zs[j + 1] - WALL_THICKNESS_M / 2.0 - fz;
            if lo_x >= hi_x || lo_z >= hi_z {
                break;
            }
            // Against a wall half of the time.
            let (x, z) = match rng.below(6) {
                0 => (lo_x, rng.range(lo_z, hi_z)),
                1 => (hi_x, rng.range(lo_z, hi_z)),
                2 => (rng.range(lo_x, hi_x), lo_z),
                _ => (rng.range(lo_x, hi_x), rng.range(lo_z, hi_z)),
            };
            let fp = (x - fx, x + fx, z - fz, z + fz);
            let overlaps = footprints
                .iter()
                .any(|o| fp.0 < o.1 && o.0 < fp.1 && fp.2 < o.3 && o.2 < fp.3);
            if overlaps {
                continue;
            }
            let objs = place_item(item, x, z, yaw);
            if objs
                .iter()
                .any(|o| aabb_distance(&o.placement, rig_pos) < k)
            {
                continue;
            }
            footprints.push(fp);
            self.objects.extend(objs);
            break;
        }
    }
}

/// The lights of a `hard` house: the ceiling light of the rig's room dimmer
/// in ambient and falling off with distance, and 1-2 more ceiling lights in
/// random rooms, so that rooms and corners differ in brightness.
fn hard_lights(
    rng: &mut Rng,
    mut main: LightSpec,
    xs: &[f64],
    zs: &[f64],
    height: f64,
) -> (LightSpec, Vec<LightSpec>) {
    main.ambient = rng.range(0.1, 0.25) as f32;
    main.diffuse = rng.range(0.7, 1.1) as f32;
    main.range_m = Some(rng.range(2.5, 6.0));
    let count = 1 + rng.below(2);
    let extra = (0..count)
        .map(|_| {
            let (i, j) = (
                rng.below(xs.len().saturating_sub(1).max(1)),
                rng.below(zs.len().saturating_sub(1).max(1)),
            );
            let at = |v: &[f64], k: usize, rng: &mut Rng| {
                let (a, b) = (
                    v.get(k).copied().unwrap_or(0.0),
                    v.get(k + 1).copied().unwrap_or(0.0),
                );
                rng.range(a.min(b) + 0.3, (a.max(b) - 0.3).max(a.min(b) + 0.3))
            };
            LightSpec {
                position_m: [at(xs, i, rng), -height + 0.3, at(zs, j, rng)],
                directional: false,
                ambient: 0.0,
                diffuse: rng.range(0.4, 0.9) as f32,
                range_m: Some(rng.range(2.0, 5.0)),
            }
        })
        .collect();
    (main, extra)
}
