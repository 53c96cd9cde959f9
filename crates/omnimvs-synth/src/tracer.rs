//! The ray tracer: a scene's primitives in the rig frame under a compressed
//! wide BVH (`obvhs`), Lambertian shading with procedural textures, and a sky
//! at infinity.

use std::time::Duration;

use fastnoise_lite::{FastNoiseLite, FractalType, NoiseType};
use glam::{Affine3A, Mat3A, Vec3A};
use nalgebra::{Matrix3, Matrix4, Point3, Vector3};
use obvhs::{BvhBuildParams, cwbvh::CwBvh, cwbvh::builder::build_cwbvh, ray::Ray, ray::RayHit};

use crate::SynthError;
use crate::mesh::{self, TriMesh};
use crate::primitive::{Prim, T_MIN};
use crate::scene::{LightSpec, SceneSpec, ShapeSpec, SkySpec};
use crate::texture::Texture;

/// The first surface along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) direction, metres.
    pub t: f32,
    /// Index of the primitive in the tracer's order.
    pub prim: u32,
}

struct Surface {
    texture: Texture,
    tex_from_rig: Affine3A,
}

#[derive(Debug, Clone)]
struct Light {
    /// Rig frame: the position of a point light, or the unit direction
    /// towards a directional one.
    v: Vec3A,
    directional: bool,
    ambient: f32,
    diffuse: f32,
    /// `1 / range_m^2` of a point light with falloff, else `None`.
    inv_range_sq: Option<f32>,
}

impl Light {
    /// The diffuse term at `p` with normal `n` (facing the viewer).
    #[inline]
    fn diffuse_at(&self, p: Vec3A, n: Vec3A) -> f32 {
        if self.directional {
            return self.diffuse * n.dot(self.v).max(0.0);
        }
        let to_light = self.v - p;
        let l = to_light.normalize_or_zero();
        let lit = self.diffuse * n.dot(l).max(0.0);
        match self.inv_range_sq {
            Some(k) => lit / (1.0 + to_light.length_squared() * k),
            None => lit,
        }
    }
}

struct Sky {
    spec: SkySpec,
    sun: Vec3A,
    noise: FastNoiseLite,
}

/// A scene ready to trace, in the rig frame.
pub struct Tracer {
    prims: Vec<Prim>,
    bvh: Option<CwBvh>,
    surfaces: Vec<Surface>,
    light: Light,
    /// [`SceneSpec::extra_lights`].
    extra_lights: Vec<Light>,
    sky: Option<Sky>,
    /// Rotation from the rig frame to the scene frame (for the sky).
    world_from_rig_rot: Mat3A,
}

/// User meshes, loaded once, indexed like [`SceneSpec::meshes`].
pub type MeshLibrary = [TriMesh];

fn v3(v: &Vector3<f64>) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

fn m3(m: &Matrix3<f64>) -> Mat3A {
    Mat3A::from_cols(
        v3(&m.column(0).into()),
        v3(&m.column(1).into()),
        v3(&m.column(2).into()),
    )
}

fn affine(m: &Matrix4<f64>) -> Affine3A {
    let lin: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into();
    let t: Vector3<f64> = m.fixed_view::<3, 1>(0, 3).into();
    Affine3A::from_mat3_translation(m3(&lin).into(), v3(&t).into())
}

fn check_finite(what: &str, values: &[f64]) -> Result<(), SynthError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SynthError::invalid(what, "expected finite numbers"))
    }
}

impl Tracer {
    /// Builds the tracer of a scene. `meshes` holds the loaded files of
    /// [`SceneSpec::meshes`] (may be empty when no object uses one).
    ///
    /// # Errors
    /// [`SynthError::Invalid`] for a non-finite or degenerate placement, or a
    /// user mesh index out of range.
    pub fn new(spec: &SceneSpec, meshes: &MeshLibrary) -> Result<Self, SynthError> {
        let w = &spec.world_from_rig;
        check_finite("world_from_rig", &[w.rotation, w.translation_m].concat())?;
        let rig_from_world = w.isometry().inverse();
        let rig_from_world_m: Matrix4<f64> = rig_from_world.to_homogeneous();
        let mut prims = Vec::new();
        let mut surfaces = Vec::with_capacity(spec.objects.len());
        for (i, obj) in spec.objects.iter().enumerate() {
            let what = || format!("objects[{i}].placement");
            let p = &obj.placement;
            check_finite(&what(), &[p.rotation, p.translation_m, p.scale].concat())?;
            if p.scale.iter().any(|s| s.abs() < 1e-9) {
                return Err(SynthError::invalid(what(), "scale must not be zero"));
            }
            if !(obj.texture_scale_m.is_finite() && obj.texture_scale_m > 0.0) {
                return Err(SynthError::invalid(
                    format!("objects[{i}].texture_scale_m"),
                    "expected a positive number",
                ));
            }
            let rig_from_obj = rig_from_world_m * p.matrix();
            let tex_from_world = p.isometry().inverse().to_homogeneous() / obj.texture_scale_m;
            let mut tex_from_rig = tex_from_world * rig_from_world.inverse().to_homogeneous();
            tex_from_rig[(3, 3)] = 1.0;
            surfaces.push(Surface {
                texture: Texture::new(&obj.texture),
                tex_from_rig: affine(&tex_from_rig),
            });
            add_shape(&mut prims, &obj.shape, &rig_from_obj, i as u32, meshes)?;
        }
        let bvh = if prims.is_empty() {
            None
        } else {
            let mut t = Duration::ZERO;
            let bvh = build_cwbvh(&prims, BvhBuildParams::fast_build(), &mut t);
            // Store the primitives in BVH order: no indirection when tracing.
            prims = bvh
                .primitive_indices
                .iter()
                .map(|&i| prims[i as usize])
                .collect();
            Some(bvh)
        };
        let rot_rig_from_world = rig_from_world.rotation.to_rotation_matrix();
        let light = make_light(&spec.light, &rig_from_world);
        let extra_lights = spec
            .extra_lights
            .iter()
            .map(|l| make_light(l, &rig_from_world))
            .collect();
        let sky = spec.sky.as_ref().map(|s| {
            let mut noise = FastNoiseLite::with_seed(s.cloud_seed);
            noise.set_noise_type(Some(NoiseType::OpenSimplex2));
            noise.set_frequency(Some(1.0));
            noise.set_fractal_type(Some(FractalType::FBm));
            noise.set_fractal_octaves(Some(5));
            Sky {
                spec: s.clone(),
                sun: Vec3A::from_array(s.sun_dir).normalize_or(Vec3A::NEG_Y),
                noise,
            }
        });
        Ok(Self {
            prims,
            bvh,
            surfaces,
            light,
            extra_lights,
            sky,
            world_from_rig_rot: m3(rot_rig_from_world.inverse().matrix()),
        })
    }

    /// Number of primitives (triangles, rectangles, ellipsoids).
    pub fn num_primitives(&self) -> usize {
        self.prims.len()
    }

    /// The first surface hit by the ray `o + t d`, `d` a unit vector in the
    /// rig frame.
    #[inline]
    pub fn intersect(&self, o: Vec3A, d: Vec3A) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let ray = Ray::new(o, d, T_MIN, f32::INFINITY);
        let mut hit = RayHit::none();
        let prims = &self.prims;
        if bvh.ray_traverse(ray, &mut hit, |r, id| {
            prims[id].intersect(r.origin, r.direction, r.tmax)
        }) {
            Some(Hit {
                t: hit.t,
                prim: hit.primitive_id,
            })
        } else {
            None
        }
    }

    /// Inverse depth (1/m) seen from the rig origin along the unit direction
    /// `d`; 0 for the sky (or nothing).
    #[inline]
    pub fn inverse_depth(&self, d: Vec3A) -> f32 {
        match self.intersect(Vec3A::ZERO, d) {
            Some(h) => 1.0 / h.t,
            None => 0.0,
        }
    }

    /// The brightness (`[0, 1]`) seen along the ray `o + t d`, `d` unit.
    #[inline]
    pub fn radiance(&self, o: Vec3A, d: Vec3A) -> f32 {
        let Some(hit) = self.intersect(o, d) else {
            return self.sky_radiance(d);
        };
        let prim = &self.prims[hit.prim as usize];
        let p = o + d * hit.t;
        let mut n = prim.normal(p);
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let surface = &self.surfaces[prim.object() as usize];
        let albedo = surface
            .texture
            .reflectance(surface.tex_from_rig.transform_point3a(p));
        let mut shade = self.light.ambient + self.light.diffuse_at(p, n);
        for extra in &self.extra_lights {
            shade += extra.ambient + extra.diffuse_at(p, n);
        }
        (albedo * shade).clamp(0.0, 1.0)
    }

    fn sky_radiance(&self, d_rig: Vec3A) -> f32 {
        let Some(sky) = &self.sky else {
            return 0.0;
        };
        let s = &sky.spec;
        let d = self.world_from_rig_rot * d_rig;
        let up = -d.y; // the scene frame has y down
        let base = if up >= 0.0 {
            s.horizon + (s.zenith - s.horizon) * up.sqrt()
        } else {
            s.ground + (s.horizon - s.ground) * (1.0 + up).powi(8)
        };
        let q = d * s.cloud_freq;
        let n = sky.noise.get_noise_3d(q.x, q.y, q.z) * 0.5 + 0.5;
        let cover = smoothstep(1.0 - s.cloud_cover, 1.0 - s.cloud_cover + 0.25, n);
        let v = base + (s.cloud_brightness - base) * cover;
        let sun = s.sun_strength * d.dot(sky.sun).max(0.0).powi(64);
        (v + sun).clamp(0.0, 1.0)
    }
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn make_light(spec: &LightSpec, rig_from_world: &nalgebra::Isometry3<f64>) -> Light {
    let v = Vector3::from(spec.position_m);
    let v = if spec.directional {
        (rig_from_world.rotation * v).normalize()
    } else {
        (rig_from_world * Point3::from(v)).coords
    };
    Light {
        v: v3(&v),
        directional: spec.directional,
        ambient: spec.ambient,
        diffuse: spec.diffuse,
        inv_range_sq: match spec.range_m {
            Some(r) if !spec.directional && r > 0.0 => Some((1.0 / (r * r)) as f32),
            _ => None,
        },
    }
}

fn add_shape(
    prims: &mut Vec<Prim>,
    shape: &ShapeSpec,
    rig_from_obj: &Matrix4<f64>,
    obj: u32,
    meshes: &MeshLibrary,
) -> Result<(), SynthError> {
    let lin: Matrix3<f64> = rig_from_obj.fixed_view::<3, 3>(0, 0).into();
    let t: Vector3<f64> = rig_from_obj.fixed_view::<3, 1>(0, 3).into();
    let xf = |p: Vector3<f64>| v3(&(lin * p + t));
    let mut rect = |corner: Vector3<f64>, u: Vector3<f64>, v: Vector3<f64>| {
        let (u, v) = (lin * u, lin * v);
        let n = u.cross(&v);
        prims.push(Prim::Rect {
            corner: xf(corner),
            u: v3(&u),
            v: v3(&v),
            w: v3(&(n / n.norm_squared())),
            obj,
        });
    };
    let mesh = match shape {
        ShapeSpec::Sphere => {
            let inv = lin
                .try_inverse()
                .ok_or_else(|| SynthError::invalid("sphere placement", "singular transform"))?;
            let half: Vector3<f64> = Vector3::from_fn(|r, _| lin.row(r).norm());
            prims.push(Prim::Ellipsoid {
                inv: m3(&inv),
                inv_t: v3(&(-(inv * t))),
                lo: v3(&(t - half)),
                hi: v3(&(t + half)),
                obj,
            });
            return Ok(());
        }
        ShapeSpec::Box => {
            for axis in 0..3 {
                let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
                for sign in [-1.0, 1.0] {
                    let mut corner = Vector3::from_element(-1.0);
                    corner[axis] = sign;
                    let mut u = Vector3::zeros();
                    u[a1] = 2.0;
                    let mut v = Vector3::zeros();
                    v[a2] = 2.0;
                    rect(corner, u, v);
                }
            }
            return Ok(());
        }
        ShapeSpec::Rect => {
            rect(
                Vector3::new(-1.0, 0.0, -1.0),
                Vector3::new(2.0, 0.0, 0.0),
                Vector3::new(0.0, 0.0, 2.0),
            );
            return Ok(());
        }
        ShapeSpec::Cylinder { segments } => mesh::cylinder((*segments).clamp(3, 1024)),
        ShapeSpec::Cone { segments } => mesh::cone((*segments).clamp(3, 1024)),
        ShapeSpec::Torus {
            minor,
            major_segments,
            minor_segments,
        } => mesh::torus(
            (*major_segments).clamp(3, 1024),
            (*minor_segments).clamp(3, 1024),
            minor.clamp(0.01, 0.5),
        ),
        ShapeSpec::Blob {
            seed,
            amplitude,
            frequency,
            subdivisions,
        } => mesh::blob(*seed, *amplitude, *frequency, (*subdivisions).min(5)),
        ShapeSpec::Extrusion {
            seed,
            corners,
            layers,
            twist,
            taper,
        } => mesh::extrusion(
            *seed,
            (*corners).clamp(3, 256),
            (*layers).clamp(1, 64),
            *twist,
            *taper,
        ),
        ShapeSpec::Tube { segments, inner } => mesh::tube((*segments).clamp(3, 1024), *inner),
        ShapeSpec::Grid {
            cells_x,
            cells_z,
            bar,
            half_y,
        } => mesh::grid(*cells_x, *cells_z, *bar, *half_y),
        ShapeSpec::Lattice { cells, bar } => mesh::lattice(*cells, *bar),
        ShapeSpec::UserMesh { index } => {
            let m = meshes.get(*index).ok_or_else(|| {
                SynthError::invalid(
                    "user mesh index",
                    format!(
                        "object refers to mesh {index} but {} are loaded",
                        meshes.len()
                    ),
                )
            })?;
            add_mesh(prims, m, &xf, obj);
            return Ok(());
        }
    };
    add_mesh(prims, &mesh, &xf, obj);
    Ok(())
}

fn add_mesh(prims: &mut Vec<Prim>, mesh: &TriMesh, xf: &impl Fn(Vector3<f64>) -> Vec3A, obj: u32) {
    let world: Vec<Vec3A> = mesh
        .positions
        .iter()
        .map(|p| xf(Vector3::new(f64::from(p.x), f64::from(p.y), f64::from(p.z))))
        .collect();
    for &[a, b, c] in &mesh.triangles {
        let (a, b, c) = (world[a as usize], world[b as usize], world[c as usize]);
        let (e1, e2) = (b - a, c - a);
        if e1.cross(e2).length_squared() > 0.0 {
            prims.push(Prim::Tri { v0: a, e1, e2, obj });
        }
    }
}
