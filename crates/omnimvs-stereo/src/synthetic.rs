//! Analytic textured scenes rendered exactly through a rig's camera models,
//! with their ground-truth inverse depth: fixtures for tests, for tuning the
//! SGM penalties and for benchmarks, independent of any dataset on disk.
//!
//! A scene is a few surfaces (an enclosing room or sphere, boxes and balls
//! inside) in the rig frame; its texture is 3D value noise of the surface
//! point, so that every camera sees the same pattern at the same place.

use omnimvs_camera::nalgebra::{Point3, Vector3};
use omnimvs_camera::{Camera, CameraModel, OcamModel, Pixel, Pose, Rig};
use omnimvs_data::gt::InvDepthMap;
use omnimvs_sweep::{EquirectGrid, GrayImage};
use rayon::prelude::*;

/// A rig like the published "Sunny"/OmniThings one: four 220-degree fisheye
/// cameras on a square of 0.6 m half-diagonal, looking front, right, back and
/// left, with images of `768 x 800` pixels times `scale` (the intrinsics are
/// scaled with them).
pub fn fixture_rig(scale: f64) -> Rig {
    let poly = [-1.966_560e2, 0.0, 3.053_428e-3, -9.784_996e-6, 2.278_718e-8];
    let inv_poly = [
        300.888_356,
        180.967_781,
        -21.353_055,
        14.896_848,
        31.786_1,
        -12.778_866,
        -10.889_768,
        20.862_822,
        6.557_302,
        -10.383_775,
        -2.519_069,
        2.891_402,
        1.028_544,
    ];
    // z'(rho') = s z(rho'/s): a_i' = a_i s^(1-i); rho' = s rho.
    let model = OcamModel {
        poly: poly
            .iter()
            .enumerate()
            .map(|(i, a)| a * scale.powi(1 - i as i32))
            .collect(),
        inv_poly: inv_poly.iter().map(|p| p * scale).collect(),
        center_row: (383.0 + 0.5) * scale - 0.5,
        center_col: (399.0 + 0.5) * scale - 0.5,
        c: 1.0,
        d: 0.0,
        e: 0.0,
        width: (800.0 * scale).round() as u32,
        height: (768.0 * scale).round() as u32,
        max_fov_deg: 220.0,
    };
    let half_pi = std::f64::consts::FRAC_PI_2;
    let poses = [
        ([0.0, 0.0, 0.0], [0.0, 0.0, 0.6]),
        ([0.0, half_pi, 0.0], [0.6, 0.0, 0.0]),
        ([0.0, std::f64::consts::PI, 0.0], [0.0, 0.0, -0.6]),
        ([0.0, -half_pi, 0.0], [-0.6, 0.0, 0.0]),
    ];
    Rig::new(
        poses
            .iter()
            .enumerate()
            .map(|(i, &(rvec, t_m))| {
                Camera::new(
                    i as u32 + 1,
                    format!("cam{}", i + 1),
                    CameraModel::Ocam(model.clone()),
                    Pose { rvec, t_m },
                    None,
                )
            })
            .collect(),
    )
}

/// One surface of a scene, in the rig frame (metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Surface {
    /// A sphere, seen from inside or outside.
    Sphere { center: [f64; 3], radius: f64 },
    /// An axis-aligned box seen from inside (a room).
    Room { min: [f64; 3], max: [f64; 3] },
    /// An axis-aligned box seen from outside (furniture).
    Block { min: [f64; 3], max: [f64; 3] },
}

impl Surface {
    /// The smallest positive ray parameter where the ray hits the surface.
    fn hit(&self, o: &Point3<f64>, d: &Vector3<f64>) -> Option<f64> {
        const EPS: f64 = 1e-9;
        match *self {
            Self::Sphere { center, radius } => {
                let oc = o - Point3::from(center);
                let b = oc.dot(d);
                let c = oc.norm_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let s = disc.sqrt();
                [-b - s, -b + s].into_iter().find(|&t| t > EPS)
            }
            Self::Room { min, max } | Self::Block { min, max } => {
                let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
                for a in 0..3 {
                    let inv = 1.0 / d[a];
                    let (mut ta, mut tb) = ((min[a] - o[a]) * inv, (max[a] - o[a]) * inv);
                    if ta > tb {
                        std::mem::swap(&mut ta, &mut tb);
                    }
                    t0 = t0.max(ta);
                    t1 = t1.min(tb);
                }
                if t1 < t0 {
                    return None;
                }
                [t0, t1].into_iter().find(|&t| t > EPS)
            }
        }
    }
}

/// A scene of textured surfaces.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub surfaces: Vec<Surface>,
    /// Seed of the texture.
    pub texture_seed: u64,
    /// Size of the coarsest texture blobs, metres (finer octaves follow).
    pub texture_scale_m: f64,
}

/// A small deterministic generator (SplitMix64).
#[derive(Debug, Clone)]
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix(self.0)
    }

    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Value in `[-1, 1]` at an integer lattice point.
fn lattice(ix: i64, iy: i64, iz: i64, seed: u64) -> f64 {
    let h = mix(seed
        ^ (ix as u64).wrapping_mul(0x8CB9_2BA7_2F3D_8DD7)
        ^ (iy as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (iz as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F));
    (h >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Smooth 3D value noise in about `[-1, 1]`.
fn value_noise(p: &Vector3<f64>, seed: u64) -> f64 {
    let f = p.map(f64::floor);
    let t = (p - f).map(|v| v * v * (3.0 - 2.0 * v));
    let (x, y, z) = (f.x as i64, f.y as i64, f.z as i64);
    let mut acc = 0.0;
    for dz in 0..2 {
        for dy in 0..2 {
            for dx in 0..2 {
                let w = (if dx == 1 { t.x } else { 1.0 - t.x })
                    * (if dy == 1 { t.y } else { 1.0 - t.y })
                    * (if dz == 1 { t.z } else { 1.0 - t.z });
                acc += w * lattice(x + dx, y + dy, z + dz, seed);
            }
        }
    }
    acc
}

impl Scene {
    /// A sphere of `radius_m` centred on the rig: every output pixel is at
    /// the same depth (the "fronto-parallel" case of spherical sweeping).
    pub fn textured_sphere(radius_m: f64, seed: u64) -> Self {
        Self {
            surfaces: vec![Surface::Sphere {
                center: [0.0; 3],
                radius: radius_m,
            }],
            texture_seed: seed,
            texture_scale_m: 0.25,
        }
    }

    /// A random room (2.5 to 5 m to each wall, floor 1 to 1.6 m below the
    /// rig, ceiling 1.5 to 2.5 m above) with 3 to 6 boxes and balls between
    /// 1.6 and 3.5 m away. Deterministic in `seed`.
    pub fn room(seed: u64) -> Self {
        let mut rng = Rng(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x5DEE_CE66);
        let min = [
            -rng.uniform(2.5, 5.0),
            -rng.uniform(1.5, 2.5),
            -rng.uniform(2.5, 5.0),
        ];
        let max = [
            rng.uniform(2.5, 5.0),
            rng.uniform(1.0, 1.6),
            rng.uniform(2.5, 5.0),
        ];
        let mut surfaces = vec![Surface::Room { min, max }];
        let count = 3 + (rng.next() % 4) as usize;
        for _ in 0..count {
            let azimuth = rng.uniform(0.0, std::f64::consts::TAU);
            let dist = rng.uniform(1.6, 3.5);
            let size = rng.uniform(0.25, 0.6);
            let cy = rng.uniform(-0.6, 0.6);
            let c = [dist * azimuth.cos(), cy, dist * azimuth.sin()];
            // Keep objects clear of the cameras (0.6 m from the centre).
            if (c[0] * c[0] + c[2] * c[2]).sqrt() - size * 1.8 < 0.9 {
                continue;
            }
            if rng.next().is_multiple_of(2) {
                surfaces.push(Surface::Sphere {
                    center: c,
                    radius: size,
                });
            } else {
                let h = rng.uniform(0.5, 1.5);
                surfaces.push(Surface::Block {
                    min: [c[0] - size, c[1] - size * h, c[2] - size],
                    max: [c[0] + size, c[1] + size * h, c[2] + size],
                });
            }
        }
        Self {
            surfaces,
            texture_seed: seed,
            texture_scale_m: 0.3,
        }
    }

    /// The nearest hit of a ray (unit `dir`): distance and point.
    pub fn intersect(
        &self,
        origin: &Point3<f64>,
        dir: &Vector3<f64>,
    ) -> Option<(f64, Point3<f64>)> {
        let t = self
            .surfaces
            .iter()
            .filter_map(|s| s.hit(origin, dir))
            .fold(f64::INFINITY, f64::min);
        t.is_finite().then(|| (t, origin + dir * t))
    }

    /// Gray level in `[0, 255]` of a surface point: three octaves of value
    /// noise.
    pub fn intensity(&self, p: &Point3<f64>) -> f32 {
        let mut v = 0.0;
        let mut amp = 1.0;
        let mut q = p.coords / self.texture_scale_m;
        for octave in 0..3 {
            v += amp * value_noise(&q, self.texture_seed.wrapping_add(octave));
            amp *= 0.5;
            q *= 2.0;
        }
        (128.0 + 110.0 * v).clamp(0.0, 255.0) as f32
    }

    /// One camera's image, 2x2 supersampled; 0 outside the field of view.
    pub fn render_camera(&self, camera: &Camera) -> GrayImage {
        let (w, h) = (
            camera.model.width() as usize,
            camera.model.height() as usize,
        );
        let origin = camera.center_in_rig();
        let mut data = vec![0f32; w * h];
        data.par_chunks_mut(w).enumerate().for_each(|(row, out)| {
            for (col, px) in out.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (dc, dr) in [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
                    let pixel = Pixel::new(col as f64 + dc, row as f64 + dr);
                    if let Some(dir) = camera.ray_in_rig(pixel)
                        && let Some((_, p)) = self.intersect(&origin, &dir)
                    {
                        acc += self.intensity(&p);
                    }
                }
                *px = acc / 4.0;
            }
        });
        GrayImage {
            width: w,
            height: h,
            data,
        }
    }

    /// The images of every camera of `rig`.
    pub fn render_frame(&self, rig: &Rig) -> Vec<GrayImage> {
        rig.cameras.iter().map(|c| self.render_camera(c)).collect()
    }

    /// The ground-truth inverse depth (1/m, from the rig centre) on `grid`;
    /// 0 where a ray hits nothing.
    pub fn inverse_depth(&self, grid: &EquirectGrid) -> InvDepthMap {
        let origin = Point3::origin();
        let mut data = vec![0f32; grid.len()];
        data.par_chunks_mut(grid.width)
            .enumerate()
            .for_each(|(row, out)| {
                for (col, v) in out.iter_mut().enumerate() {
                    let dir = grid.ray(row as f64, col as f64);
                    *v = self
                        .intersect(&origin, &dir)
                        .map_or(0.0, |(t, _)| (1.0 / t) as f32);
                }
            });
        InvDepthMap {
            width: grid.width,
            height: grid.height,
            data,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_rig_projects_like_the_full_one() {
        let full = fixture_rig(1.0);
        let quarter = fixture_rig(0.25);
        let p = Point3::new(0.7, -0.3, 2.0);
        for (a, b) in full.cameras.iter().zip(&quarter.cameras) {
            match (a.project_rig(&p), b.project_rig(&p)) {
                (Some(pa), Some(pb)) => {
                    assert!(((pa.col + 0.5) * 0.25 - 0.5 - pb.col).abs() < 1e-6);
                    assert!(((pa.row + 0.5) * 0.25 - 0.5 - pb.row).abs() < 1e-6);
                    let ray = b.ray_in_rig(pb).unwrap();
                    let want = (p - b.center_in_rig()).normalize();
                    assert!(
                        (ray - want).norm() < 1e-3,
                        "unprojection of the scaled model"
                    );
                }
                (None, None) => {}
                _ => panic!("visibility differs"),
            }
        }
    }

    #[test]
    fn sphere_depth_and_room_hits() {
        let s = Scene::textured_sphere(3.0, 1);
        let grid = EquirectGrid::new(8, 16, 45.0).unwrap();
        assert!(
            s.inverse_depth(&grid)
                .data
                .iter()
                .all(|&d| (d - 1.0 / 3.0).abs() < 1e-6)
        );
        let room = Scene::room(7);
        let inv = room.inverse_depth(&grid);
        assert!(
            inv.data.iter().all(|&d| d > 0.1 && d < 1.0),
            "{:?}",
            inv.data
        );
        let v: Vec<f32> = (0..50)
            .map(|k| room.intensity(&Point3::new(k as f64 * 0.05, 0.3, 1.0)))
            .collect();
        let mean = v.iter().sum::<f32>() / 50.0;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / 50.0;
        assert!(var > 100.0, "texture has contrast: var {var}");
    }
}
