//! Triangle meshes in an object's unit space (inside the unit ball): the
//! generated shapes (cylinder, cone, torus, displaced sphere, extrusion) and
//! user meshes loaded from OBJ or PLY files.

use fastnoise_lite::{FastNoiseLite, FractalType, NoiseType};
use glam::Vec3A;

use crate::rng::Rng;

/// An indexed triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<Vec3A>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    fn push(&mut self, p: Vec3A) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    fn tri(&mut self, a: u32, b: u32, c: u32) {
        self.triangles.push([a, b, c]);
    }

    /// Recentres the mesh on the centre of its bounding box and scales it so
    /// that its farthest vertex lies on the unit sphere.
    pub fn normalize_to_unit_ball(&mut self) {
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for p in &self.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let c = (lo + hi) * 0.5;
        let r = self
            .positions
            .iter()
            .map(|p| (*p - c).length())
            .fold(0.0f32, f32::max);
        if r > 0.0 && r.is_finite() {
            for p in &mut self.positions {
                *p = (*p - c) / r;
            }
        }
    }
}

/// A closed cylinder of radius 1 around the y axis, `y` in `[-1, 1]`.
pub fn cylinder(segments: u32) -> TriMesh {
    frustum(segments, 1.0, 1.0)
}

/// A closed cone: apex at `y = -1`, base of radius 1 at `y = 1`.
pub fn cone(segments: u32) -> TriMesh {
    frustum(segments, 0.0, 1.0)
}

/// A closed frustum around the y axis, radius `r_top` at `y = -1` and
/// `r_bottom` at `y = 1` (y points down, as in the camera frame).
fn frustum(segments: u32, r_top: f32, r_bottom: f32) -> TriMesh {
    let n = segments.max(3);
    let mut m = TriMesh::default();
    let ring = |m: &mut TriMesh, r: f32, y: f32| -> u32 {
        let first = m.positions.len() as u32;
        for i in 0..n {
            let a = i as f32 / n as f32 * std::f32::consts::TAU;
            m.push(Vec3A::new(r * a.cos(), y, r * a.sin()));
        }
        first
    };
    let top = ring(&mut m, r_top, -1.0);
    let bottom = ring(&mut m, r_bottom, 1.0);
    let top_c = m.push(Vec3A::new(0.0, -1.0, 0.0));
    let bottom_c = m.push(Vec3A::new(0.0, 1.0, 0.0));
    for i in 0..n {
        let j = (i + 1) % n;
        if r_top > 0.0 {
            m.tri(top + i, top + j, bottom + i);
            m.tri(top_c, top + j, top + i);
        }
        m.tri(top + j, bottom + j, bottom + i);
        m.tri(bottom_c, bottom + i, bottom + j);
    }
    m
}

/// A torus in the xz plane, tube radius `minor` (in `(0, 0.5)`), outer
/// radius 1.
pub fn torus(major_segments: u32, minor_segments: u32, minor: f32) -> TriMesh {
    let (nu, nv) = (major_segments.max(3), minor_segments.max(3));
    let major = 1.0 - minor;
    let mut m = TriMesh::default();
    for i in 0..nu {
        let u = i as f32 / nu as f32 * std::f32::consts::TAU;
        for j in 0..nv {
            let v = j as f32 / nv as f32 * std::f32::consts::TAU;
            let r = major + minor * v.cos();
            m.push(Vec3A::new(r * u.cos(), minor * v.sin(), r * u.sin()));
        }
    }
    for i in 0..nu {
        for j in 0..nv {
            let a = i * nv + j;
            let b = ((i + 1) % nu) * nv + j;
            let c = ((i + 1) % nu) * nv + (j + 1) % nv;
            let d = i * nv + (j + 1) % nv;
            m.tri(a, b, c);
            m.tri(a, c, d);
        }
    }
    m
}

/// A unit icosphere with `subdivisions` levels of 4:1 splitting.
pub fn icosphere(subdivisions: u32) -> TriMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut m = TriMesh::default();
    for p in [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ] {
        m.push(Vec3A::from_array(p).normalize());
    }
    m.triangles = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions.min(6) {
        let mut cache = std::collections::HashMap::new();
        let mut tris = Vec::with_capacity(m.triangles.len() * 4);
        let old = std::mem::take(&mut m.triangles);
        for [a, b, c] in old {
            let mut mid = |x: u32, y: u32, m: &mut TriMesh| -> u32 {
                let key = (x.min(y), x.max(y));
                *cache.entry(key).or_insert_with(|| {
                    let p = (m.positions[x as usize] + m.positions[y as usize]).normalize();
                    m.push(p)
                })
            };
            let ab = mid(a, b, &mut m);
            let bc = mid(b, c, &mut m);
            let ca = mid(c, a, &mut m);
            tris.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        m.triangles = tris;
    }
    m
}

/// An irregular closed surface: an icosphere whose vertices are moved along
/// their radius by fractal noise (`amplitude` relative to the radius), then
/// rescaled into the unit ball.
pub fn blob(seed: i32, amplitude: f32, frequency: f32, subdivisions: u32) -> TriMesh {
    let mut m = icosphere(subdivisions);
    let mut noise = FastNoiseLite::with_seed(seed);
    noise.set_noise_type(Some(NoiseType::OpenSimplex2));
    noise.set_frequency(Some(frequency));
    noise.set_fractal_type(Some(FractalType::FBm));
    noise.set_fractal_octaves(Some(3));
    for p in &mut m.positions {
        let k = (1.0 + amplitude * noise.get_noise_3d(p.x, p.y, p.z)).max(0.2);
        *p *= k;
    }
    m.normalize_to_unit_ball();
    m
}

/// An irregular prism: a random star-shaped polygon of `corners` corners
/// (radii in `[0.35, 1]`) swept along y from -1 to 1 in `layers` steps,
/// twisted by `twist` radians and tapered by `taper` (radius factor at the
/// bottom).
pub fn extrusion(seed: u64, corners: u32, layers: u32, twist: f32, taper: f32) -> TriMesh {
    let n = corners.max(3);
    let layers = layers.max(1);
    let mut rng = Rng::new(seed);
    let radii: Vec<f32> = (0..n).map(|_| rng.range(0.35, 1.0) as f32).collect();
    let mut m = TriMesh::default();
    for l in 0..=layers {
        let s = l as f32 / layers as f32;
        let y = -1.0 + 2.0 * s;
        let (rot, scale) = (twist * s, 1.0 + (taper - 1.0) * s);
        for (i, r) in radii.iter().enumerate() {
            let a = i as f32 / n as f32 * std::f32::consts::TAU + rot;
            m.push(Vec3A::new(r * scale * a.cos(), y, r * scale * a.sin()));
        }
    }
    for l in 0..layers {
        for i in 0..n {
            let j = (i + 1) % n;
            let (a, b) = (l * n + i, l * n + j);
            let (c, d) = ((l + 1) * n + j, (l + 1) * n + i);
            m.tri(a, b, c);
            m.tri(a, c, d);
        }
    }
    let top_c = m.push(Vec3A::new(0.0, -1.0, 0.0));
    let bottom_c = m.push(Vec3A::new(0.0, 1.0, 0.0));
    for i in 0..n {
        let j = (i + 1) % n;
        m.tri(top_c, j, i);
        m.tri(bottom_c, layers * n + i, layers * n + j);
    }
    m.normalize_to_unit_ball();
    m
}

/// An axis-aligned box from `lo` to `hi` (12 triangles), added to `m`.
fn add_box(m: &mut TriMesh, lo: Vec3A, hi: Vec3A) {
    let first = m.positions.len() as u32;
    for k in 0..8u32 {
        m.push(Vec3A::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        ));
    }
    // Two triangles per face, corners by their bit patterns (x = 1, y = 2, z = 4).
    for [a, b, c, d] in [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ] {
        m.tri(first + a, first + c, first + b);
        m.tri(first + a, first + d, first + c);
    }
}

/// A thick-walled open pipe around the y axis: outer radius 1, inner radius
/// `inner` (in `(0, 1)`), `y` in `[-1, 1]`, closed by two flat rings. Seen
/// from an open end, a concave surface.
pub fn tube(segments: u32, inner: f32) -> TriMesh {
    let n = segments.max(3);
    let inner = inner.clamp(0.05, 0.99);
    let mut m = TriMesh::default();
    // Rings: outer top, outer bottom, inner top, inner bottom.
    for (r, y) in [(1.0, -1.0), (1.0, 1.0), (inner, -1.0), (inner, 1.0)] {
        for i in 0..n {
            let a = i as f32 / n as f32 * std::f32::consts::TAU;
            m.push(Vec3A::new(r * a.cos(), y, r * a.sin()));
        }
    }
    let (ot, ob, it, ib) = (0, n, 2 * n, 3 * n);
    for i in 0..n {
        let j = (i + 1) % n;
        // Outward normals: the walls' quads are wound from p to q, flipped
        // where that would face into the solid.
        for (p, q, flip) in [
            (ot, ob, true),
            (it, ib, false),
            (ot, it, false),
            (ob, ib, true),
        ] {
            if flip {
                m.tri(p + i, q + j, p + j);
                m.tri(p + i, q + i, q + j);
            } else {
                m.tri(p + i, p + j, q + j);
                m.tri(p + i, q + j, q + i);
            }
        }
    }
    m
}

/// A flat grid in the xz plane: a frame of bars (width `bar`, in unit-space
/// units) around `cells_x x cells_z` square holes, thickness `2 * half_y`
/// along y. One cell is a picture frame, several a plate with holes.
pub fn grid(cells_x: u32, cells_z: u32, bar: f32, half_y: f32) -> TriMesh {
    let (nx, nz) = (cells_x.clamp(1, 64), cells_z.clamp(1, 64));
    let bar = bar.clamp(0.005, 0.5);
    let half_y = half_y.clamp(0.002, 1.0);
    let mut m = TriMesh::default();
    let h = bar / 2.0;
    for i in 0..=nx {
        let x = -1.0 + h + (2.0 - bar) * i as f32 / nx as f32;
        add_box(
            &mut m,
            Vec3A::new(x - h, -half_y, -1.0),
            Vec3A::new(x + h, half_y, 1.0),
        );
    }
    for k in 0..=nz {
        let z = -1.0 + h + (2.0 - bar) * k as f32 / nz as f32;
        add_box(
            &mut m,
            Vec3A::new(-1.0, -half_y, z - h),
            Vec3A::new(1.0, half_y, z + h),
        );
    }
    m
}

/// A 3D lattice ("jungle gym"): bars of width `bar` along x, y and z through
/// the `(cells + 1)^2` grid points of each face direction of `[-1, 1]^3`.
pub fn lattice(cells: u32, bar: f32) -> TriMesh {
    let n = cells.clamp(1, 16);
    let bar = bar.clamp(0.005, 0.5);
    let h = bar / 2.0;
    let at = |i: u32| -1.0 + h + (2.0 - bar) * i as f32 / n as f32;
    let mut m = TriMesh::default();
    for axis in 0..3 {
        for i in 0..=n {
            for k in 0..=n {
                let (a, b) = (at(i), at(k));
                let mut lo = [a - h, b - h, -1.0];
                let mut hi = [a + h, b + h, 1.0];
                // Put the long side on `axis`.
                lo.rotate_right(axis);
                hi.rotate_right(axis);
                add_box(&mut m, Vec3A::from_array(lo), Vec3A::from_array(hi));
            }
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_radius(m: &TriMesh) -> f32 {
        m.positions.iter().map(|p| p.length()).fold(0.0, f32::max)
    }

    /// Signed volume by the divergence theorem: positive and close to the
    /// analytic volume for a closed, consistently oriented mesh.
    fn volume(m: &TriMesh) -> f32 {
        m.triangles
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (
                    m.positions[a as usize],
                    m.positions[b as usize],
                    m.positions[c as usize],
                );
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn thin_and_holed_shapes_stay_in_the_unit_cube_and_are_closed() {
        let inside = |m: &TriMesh| {
            m.positions
                .iter()
                .all(|p| p.abs().max_element() <= 1.0 + 1e-6)
        };
        let t = tube(64, 0.8);
        let want = 2.0 * std::f32::consts::PI * (1.0 - 0.64);
        assert!(inside(&t));
        assert!((volume(&t) - want).abs() / want < 0.01, "{}", volume(&t));
        let mut b = TriMesh::default();
        add_box(
            &mut b,
            Vec3A::new(-1.0, -0.5, 0.0),
            Vec3A::new(1.0, 0.5, 0.25),
        );
        assert!((volume(&b) - 0.5).abs() < 1e-6, "{}", volume(&b));
        let g = grid(3, 2, 0.1, 0.05);
        assert!(inside(&g));
        assert_eq!(g.triangles.len(), (4 + 3) * 12);
        let l = lattice(2, 0.08);
        assert!(inside(&l));
        assert_eq!(l.triangles.len(), 3 * 9 * 12);
        // Every bar of the lattice is positive volume: no inverted box.
        assert!(volume(&l) > 0.0);
    }

    #[test]
    fn generated_shapes_fit_the_unit_ball_and_are_closed() {
        let shapes = [
            ("cylinder", cylinder(64), 2.0 * std::f32::consts::PI),
            ("cone", cone(64), 2.0 * std::f32::consts::PI / 3.0),
            (
                "torus",
                torus(64, 32, 0.25),
                2.0 * std::f32::consts::PI.powi(2) * 0.75 * 0.25f32.powi(2),
            ),
            ("icosphere", icosphere(4), 4.0 / 3.0 * std::f32::consts::PI),
        ];
        for (name, m, want) in shapes {
            assert!(max_radius(&m) <= 1.0 * 2f32.sqrt() + 1e-5, "{name}");
            let v = volume(&m).abs();
            assert!(
                (v - want).abs() / want < 0.03,
                "{name}: volume {v} want {want}"
            );
        }
        for m in [blob(5, 0.4, 1.5, 3), extrusion(9, 7, 4, 1.0, 0.6)] {
            assert!((max_radius(&m) - 1.0).abs() < 1e-5);
            assert!(volume(&m).abs() > 0.1);
        }
    }
}
