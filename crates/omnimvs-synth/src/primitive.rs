//! The primitives the ray tracer intersects, in the rig frame: triangles,
//! rectangles (exact planes: box faces, walls) and ellipsoids (exact
//! spheres). One file, one `match`: the set is closed and small.

use glam::{Mat3A, Vec3A};
use obvhs::{Boundable, aabb::Aabb};

/// Rays start this far along their direction (metres), so that a surface
/// through the ray origin does not hit itself.
pub const T_MIN: f32 = 1e-4;

#[derive(Debug, Clone, Copy)]
pub enum Prim {
    Tri {
        v0: Vec3A,
        e1: Vec3A,
        e2: Vec3A,
        obj: u32,
    },
    /// The parallelogram `corner + a u + b v`, `a, b` in `[0, 1]`;
    /// `w = (u x v) / |u x v|^2`.
    Rect {
        corner: Vec3A,
        u: Vec3A,
        v: Vec3A,
        w: Vec3A,
        obj: u32,
    },
    /// The ellipsoid `|inv * p + inv_t| = 1`.
    Ellipsoid {
        inv: Mat3A,
        inv_t: Vec3A,
        lo: Vec3A,
        hi: Vec3A,
        obj: u32,
    },
}

impl Prim {
    pub fn object(&self) -> u32 {
        match self {
            Self::Tri { obj, .. } | Self::Rect { obj, .. } | Self::Ellipsoid { obj, .. } => *obj,
        }
    }

    /// The distance along `d` to the nearest intersection in `(T_MIN, t_max)`,
    /// or infinity.
    #[inline]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, t_max: f32) -> f32 {
        let t = match self {
            Self::Tri { v0, e1, e2, .. } => {
                let p = d.cross(*e2);
                let det = e1.dot(p);
                if det.abs() < 1e-20 {
                    return f32::INFINITY;
                }
                let inv = 1.0 / det;
                let s = o - *v0;
                let a = s.dot(p) * inv;
                if !(0.0..=1.0).contains(&a) {
                    return f32::INFINITY;
                }
                let q = s.cross(*e1);
                let b = d.dot(q) * inv;
                if b < 0.0 || a + b > 1.0 {
                    return f32::INFINITY;
                }
                e2.dot(q) * inv
            }
            Self::Rect {
                corner, u, v, w, ..
            } => {
                let denom = w.dot(d);
                if denom == 0.0 {
                    return f32::INFINITY;
                }
                let t = w.dot(*corner - o) / denom;
                if !(t > T_MIN && t < t_max) {
                    return f32::INFINITY;
                }
                let p = o + d * t - *corner;
                let a = w.dot(p.cross(*v));
                let b = w.dot(u.cross(p));
                if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) {
                    return f32::INFINITY;
                }
                t
            }
            Self::Ellipsoid { inv, inv_t, .. } => {
                let o2 = *inv * o + *inv_t;
                let d2 = *inv * d;
                let a = d2.length_squared();
                let t0 = -o2.dot(d2) / a;
                // Closest approach to the centre, squared: stable for far objects.
                let h = o2 + d2 * t0;
                let disc = 1.0 - h.length_squared();
                if disc < 0.0 {
                    return f32::INFINITY;
                }
                let s = (disc / a).sqrt();
                if t0 - s > T_MIN { t0 - s } else { t0 + s }
            }
        };
        if t > T_MIN && t < t_max {
            t
        } else {
            f32::INFINITY
        }
    }

    /// The unit geometric normal at `p` (a point on the surface), either side.
    #[inline]
    pub fn normal(&self, p: Vec3A) -> Vec3A {
        match self {
            Self::Tri { e1, e2, .. } => e1.cross(*e2).normalize_or(Vec3A::Y),
            Self::Rect { w, .. } => w.normalize_or(Vec3A::Y),
            Self::Ellipsoid { inv, inv_t, .. } => {
                let local = *inv * p + *inv_t;
                (inv.transpose() * local).normalize_or(Vec3A::Y)
            }
        }
    }
}

impl Boundable for Prim {
    fn aabb(&self) -> Aabb {
        match self {
            Self::Tri { v0, e1, e2, .. } => Aabb::from_points(&[*v0, *v0 + *e1, *v0 + *e2]),
            Self::Rect { corner, u, v, .. } => {
                Aabb::from_points(&[*corner, *corner + *u, *corner + *v, *corner + *u + *v])
            }
            Self::Ellipsoid { lo, hi, .. } => Aabb::new(*lo, *hi),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipsoid_from_inside_hits_far_side_exactly() {
        let r = 3.7f32;
        let e = Prim::Ellipsoid {
            inv: Mat3A::from_diagonal(glam::Vec3::splat(1.0 / r)),
            inv_t: Vec3A::ZERO,
            lo: Vec3A::splat(-r),
            hi: Vec3A::splat(r),
            obj: 0,
        };
        let d = Vec3A::new(0.3, -0.5, 0.8).normalize();
        let t = e.intersect(Vec3A::ZERO, d, f32::INFINITY);
        assert!((t - r).abs() <= 2.0 * f32::EPSILON * r, "{t}");
        // From outside: the near side.
        let t = e.intersect(Vec3A::new(0.0, 0.0, -10.0), Vec3A::Z, f32::INFINITY);
        assert!((t - (10.0 - r)).abs() < 1e-5);
        assert!(
            e.intersect(Vec3A::new(0.0, 5.0, -10.0), Vec3A::Z, f32::INFINITY)
                .is_infinite()
        );
    }

    #[test]
    fn rect_and_triangle_hits_and_misses() {
        let (u, v) = (Vec3A::new(2.0, 0.0, 0.0), Vec3A::new(0.0, 2.0, 0.0));
        let n = u.cross(v);
        let rect = Prim::Rect {
            corner: Vec3A::new(-1.0, -1.0, 5.0),
            u,
            v,
            w: n / n.length_squared(),
            obj: 0,
        };
        assert_eq!(rect.intersect(Vec3A::ZERO, Vec3A::Z, f32::INFINITY), 5.0);
        assert!(
            rect.intersect(Vec3A::ZERO, Vec3A::new(0.5, 0.0, 1.0).normalize(), 1.0)
                .is_infinite()
        );
        assert_eq!(
            rect.intersect(Vec3A::ZERO, Vec3A::new(0.1, 0.0, 1.0), f32::INFINITY),
            5.0
        );
        assert!(
            rect.intersect(Vec3A::ZERO, Vec3A::new(1.0, 0.0, 1.0), f32::INFINITY)
                .is_infinite()
        );
        let tri = Prim::Tri {
            v0: Vec3A::new(0.0, 0.0, 2.0),
            e1: Vec3A::new(1.0, 0.0, 0.0),
            e2: Vec3A::new(0.0, 1.0, 0.0),
            obj: 0,
        };
        let t = tri.intersect(Vec3A::new(0.2, 0.2, 0.0), Vec3A::Z, f32::INFINITY);
        assert!((t - 2.0).abs() < 1e-6);
        assert!(
            tri.intersect(Vec3A::new(0.8, 0.8, 0.0), Vec3A::Z, f32::INFINITY)
                .is_infinite()
        );
        assert!((tri.normal(Vec3A::ZERO) - Vec3A::Z).length() < 1e-6);
    }
}
