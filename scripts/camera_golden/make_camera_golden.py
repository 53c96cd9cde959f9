#!/usr/bin/env python3
"""Golden values for the closed-form camera models of omnimvs-camera.

Written from the published formulas alone (numpy, float64, no code shared with
the Rust implementation):

* ds: Usenko, Demmel and Cremers, "The Double Sphere Camera Model", 3DV 2018:
  projection (built here geometrically: unit sphere, shift by xi, second unit
  sphere, pinhole shifted by alpha / (1 - alpha)), the validity condition
  z > -w2 |p| with w1, w2 of the paper, and the closed-form unprojection on
  r^2 <= 1 / (2 alpha - 1) for alpha > 0.5.
* eucm: Khomutenko, Garcia and Martinet, "An Enhanced Unified Camera Model",
  RA-L 2016 (in the notation of the double sphere paper): z > -w d, the
  unprojection on r^2 <= 1 / (beta (2 alpha - 1)) for alpha > 0.5.
* ucm: Mei and Rives, ICRA 2007, as Kalibr's `omni` + `radtan`:
  m = (x, y) / (z + xi |p|), then radial-tangential distortion. Valid for
  z > -xi |p| (xi <= 1) or z > -|p| / xi (xi > 1, where |m| peaks at
  1 / sqrt(xi^2 - 1)).
* kb4: OpenCV's fisheye module, theta_d = theta (1 + k1 theta^2 + k2 theta^4
  + k3 theta^6 + k4 theta^8), valid up to half the field of view.
* pinhole-radtan: OpenCV's pinhole model with (k1, k2, p1, p2).

With radial-tangential distortion the domain is where the distortion is
one-to-one: |m|^2 below the first positive root of d/dr [r (1 + k1 r^2 +
k2 r^4)] = 1 + 3 k1 r^2 + 5 k2 r^4, and a positive Jacobian determinant.
Iterative inverses (KB4's theta, the distortion) are Newton solves in float64
converged to 1e-14, cross-checked by projecting the result back; the radial
models' closed-form unprojections are cross-checked by a bisection on the
angle from the optical axis.

Conventions: camera frame x right, y down, z forward; pixels (col, row),
0-based, centres at integers; fx, cx along columns.

Usage (from the repository root):
    python3 scripts/camera_golden/make_camera_golden.py
writes crates/omnimvs-camera/tests/golden/camera_models.json.
"""
import json
import math
import os

import numpy as np

OUT = os.path.join("crates", "omnimvs-camera", "tests", "golden", "camera_models.json")
# Smallest distance (radians, or relative radius) between a golden input and
# its model's domain boundary, so that rounding cannot flip the expectation.
MARGIN = 1e-7


def unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def angle_between(a, b):
    return math.atan2(np.linalg.norm(np.cross(a, b)), float(np.dot(a, b)))


def bisect(f, lo, hi, iters=200):
    """Root of f on [lo, hi] with f(lo), f(hi) of opposite signs."""
    flo = f(lo)
    assert flo * f(hi) <= 0.0, (lo, hi, flo, f(hi))
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        fm = f(mid)
        if (fm <= 0.0) == (flo <= 0.0):
            lo, flo = mid, fm
        else:
            hi = mid
    return 0.5 * (lo + hi)


# --------------------------------------------------------------------------
# Radial-tangential distortion (OpenCV, Kalibr).
# --------------------------------------------------------------------------
class RadTan:
    def __init__(self, k1, k2, p1, p2):
        self.k1, self.k2, self.p1, self.p2 = k1, k2, p1, p2

    def distort(self, m):
        x, y = m
        r2 = x * x + y * y
        radial = 1.0 + self.k1 * r2 + self.k2 * r2 * r2
        return np.array([
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        ])

    def jacobian(self, m):
        x, y = m
        r2 = x * x + y * y
        radial = 1.0 + self.k1 * r2 + self.k2 * r2 * r2
        # d radial / dx = x (2 k1 + 4 k2 r2), likewise for y.
        g = 2.0 * self.k1 + 4.0 * self.k2 * r2
        return np.array([
            [radial + x * x * g + 2.0 * self.p1 * y + 6.0 * self.p2 * x,
             x * y * g + 2.0 * self.p1 * x + 2.0 * self.p2 * y],
            [x * y * g + 2.0 * self.p1 * x + 2.0 * self.p2 * y,
             radial + y * y * g + 6.0 * self.p1 * y + 2.0 * self.p2 * x],
        ])

    def fold_r2(self):
        """First positive s = r^2 with 1 + 3 k1 s + 5 k2 s^2 = 0, or inf."""
        roots = np.roots([5.0 * self.k2, 3.0 * self.k1, 1.0]) if self.k2 != 0.0 else (
            np.array([-1.0 / (3.0 * self.k1)]) if self.k1 != 0.0 else np.array([]))
        real = [r.real for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and r.real > 0.0]
        return min(real) if real else math.inf

    def valid_margin(self, m):
        """Positive inside the one-to-one domain: min of the relative r^2
        margin to the fold and the Jacobian determinant."""
        r2 = float(m[0] ** 2 + m[1] ** 2)
        fold = self.fold_r2()
        radial = 1.0 - r2 / fold if math.isfinite(fold) else 1.0
        return min(radial, float(np.linalg.det(self.jacobian(m))))

    def undistort(self, md):
        """Newton solve of distort(m) = md from md, to 1e-14."""
        md = np.asarray(md, dtype=np.float64)
        m = md.copy()
        for _ in range(200):
            res = self.distort(m) - md
            step = np.linalg.solve(self.jacobian(m), res)
            # Damp a step that would increase the residual.
            t = 1.0
            while t > 1e-6 and np.abs(self.distort(m - t * step) - md).max() > np.abs(res).max():
                t *= 0.5
            m = m - t * step
            if np.abs(t * step).max() <= 1e-14 * (1.0 + np.abs(m).max()):
                res = self.distort(m) - md
                assert np.abs(res).max() <= 1e-14 * (1.0 + np.abs(md).max()), res
                return m
        raise RuntimeError(f"undistort did not converge for {md}")


NO_DISTORTION = RadTan(0.0, 0.0, 0.0, 0.0)


# --------------------------------------------------------------------------
# Models. Each has: fx, fy, cx, cy, half_fov (radians), project(p) -> (col,
# row) or None, unproject(col, row) -> unit ray or None, and for the radial
# ones radius(theta) (image-plane radius at angle theta) for the cross-check.
# --------------------------------------------------------------------------
class Model:
    radial = True

    def pixel(self, mx, my):
        return (self.fx * mx + self.cx, self.fy * my + self.cy)

    def plane(self, col, row):
        return ((col - self.cx) / self.fx, (row - self.cy) / self.fy)

    def unproject_by_bisection(self, col, row):
        """The ray of a pixel of a radial model: the angle theta in
        [0, half_fov] whose image radius is that of the pixel."""
        mx, my = self.plane(col, row)
        r = math.hypot(mx, my)
        if r == 0.0:
            return np.array([0.0, 0.0, 1.0])
        hi = self.half_fov * (1.0 - 1e-15)
        theta = bisect(lambda t: self.radius(t) - r, 0.0, hi)
        s = math.sin(theta) / r
        return np.array([s * mx, s * my, math.cos(theta)])


class DoubleSphere(Model):
    def __init__(self, fx, fy, cx, cy, xi, alpha):
        self.fx, self.fy, self.cx, self.cy, self.xi, self.alpha = fx, fy, cx, cy, xi, alpha
        w1 = alpha / (1.0 - alpha) if alpha <= 0.5 else (1.0 - alpha) / alpha
        self.w2 = (w1 + xi) / math.sqrt(2.0 * w1 * xi + xi * xi + 1.0)
        self.half_fov = math.acos(-self.w2)
        self.r2_max = 1.0 / (2.0 * alpha - 1.0) if alpha > 0.5 else math.inf

    def domain_margin(self, p):
        theta = math.atan2(math.hypot(p[0], p[1]), p[2])
        return self.half_fov - theta

    def plane_point(self, p):
        # Unit sphere, shifted by xi, second unit sphere, pinhole at
        # -alpha / (1 - alpha) behind the second sphere's centre.
        q = unit(p) + np.array([0.0, 0.0, self.xi])
        q = unit(q)
        zeta = self.alpha / (1.0 - self.alpha) if self.alpha < 1.0 else math.inf
        denom = (1.0 - self.alpha) * (q[2] + zeta)
        return q[0] / denom, q[1] / denom

    def project(self, p):
        if np.linalg.norm(p) == 0.0 or not p[2] > -self.w2 * np.linalg.norm(p):
            return None
        return self.pixel(*self.plane_point(p))

    def radius(self, theta):
        return math.hypot(*self.plane_point(np.array([math.sin(theta), 0.0, math.cos(theta)])))

    def pixel_margin(self, col, row):
        mx, my = self.plane(col, row)
        return 1.0 - (mx * mx + my * my) / self.r2_max

    def unproject(self, col, row):
        mx, my = self.plane(col, row)
        r2 = mx * mx + my * my
        a, xi = self.alpha, self.xi
        if r2 > self.r2_max:
            return None
        mz = (1.0 - a * a * r2) / (a * math.sqrt(1.0 - (2.0 * a - 1.0) * r2) + 1.0 - a)
        k = (mz * xi + math.sqrt(mz * mz + (1.0 - xi * xi) * r2)) / (mz * mz + r2)
        return unit([k * mx, k * my, k * mz - xi])


class ExtendedUnified(Model):
    def __init__(self, fx, fy, cx, cy, alpha, beta):
        self.fx, self.fy, self.cx, self.cy, self.alpha, self.beta = fx, fy, cx, cy, alpha, beta
        self.w = alpha / (1.0 - alpha) if alpha <= 0.5 else (1.0 - alpha) / alpha
        # The boundary z = -w d of unit rays, solved for the angle.
        f = lambda t: math.cos(t) + self.w * math.sqrt(beta * math.sin(t) ** 2 + math.cos(t) ** 2)
        self.half_fov = bisect(f, math.pi / 2.0, math.pi)
        self.r2_max = 1.0 / (beta * (2.0 * alpha - 1.0)) if alpha > 0.5 else math.inf

    def d(self, p):
        return math.sqrt(self.beta * (p[0] ** 2 + p[1] ** 2) + p[2] ** 2)

    def domain_margin(self, p):
        theta = math.atan2(math.hypot(p[0], p[1]), p[2])
        return self.half_fov - theta

    def plane_point(self, p):
        denom = self.alpha * self.d(p) + (1.0 - self.alpha) * p[2]
        return p[0] / denom, p[1] / denom

    def project(self, p):
        d = self.d(p)
        if d == 0.0 or not p[2] > -self.w * d:
            return None
        return self.pixel(*self.plane_point(p))

    def radius(self, theta):
        return math.hypot(*self.plane_point(np.array([math.sin(theta), 0.0, math.cos(theta)])))

    def pixel_margin(self, col, row):
        mx, my = self.plane(col, row)
        return 1.0 - (mx * mx + my * my) / self.r2_max

    def unproject(self, col, row):
        mx, my = self.plane(col, row)
        r2 = mx * mx + my * my
        a, b = self.alpha, self.beta
        if r2 > self.r2_max:
            return None
        mz = (1.0 - b * a * a * r2) / (a * math.sqrt(1.0 - (2.0 * a - 1.0) * b * r2) + 1.0 - a)
        return unit([mx, my, mz])


class Unified(Model):
    def __init__(self, fx, fy, cx, cy, xi, distortion=NO_DISTORTION):
        self.fx, self.fy, self.cx, self.cy, self.xi = fx, fy, cx, cy, xi
        self.dist = distortion
        self.radial = distortion.p1 == 0.0 and distortion.p2 == 0.0
        # Sphere domain: z > -w |p|.
        self.w = xi if xi <= 1.0 else 1.0 / xi
        sphere = math.acos(-self.w)
        self.r2_max = 1.0 / (xi * xi - 1.0) if xi > 1.0 else math.inf
        fold = distortion.fold_r2()
        half = sphere
        if math.isfinite(fold):
            # The angle whose undistorted radius reaches the fold, if any.
            g = lambda t: math.sin(t) / (math.cos(t) + xi) - math.sqrt(fold)
            if g(sphere * (1.0 - 1e-12)) > 0.0:
                half = bisect(g, 0.0, sphere * (1.0 - 1e-12))
        self.half_fov = half

    def undistorted(self, p):
        return p[0] / (p[2] + self.xi * np.linalg.norm(p)), p[1] / (p[2] + self.xi * np.linalg.norm(p))

    def domain_margin(self, p):
        theta = math.atan2(math.hypot(p[0], p[1]), p[2])
        sphere = math.acos(-self.w) - theta
        if sphere <= 0.0:
            return sphere
        return min(sphere, self.dist.valid_margin(self.undistorted(p)))

    def project(self, p):
        n = np.linalg.norm(p)
        if n == 0.0 or not p[2] > -self.w * n:
            return None
        m = np.array(self.undistorted(p))
        if self.dist.valid_margin(m) <= 0.0:
            return None
        return self.pixel(*self.dist.distort(m))

    def radius(self, theta):
        m = np.array(self.undistorted(np.array([math.sin(theta), 0.0, math.cos(theta)])))
        return float(self.dist.distort(m)[0])

    def pixel_margin(self, col, row):
        m = self.dist.undistort(self.plane(col, row))
        return 1.0 - float(m @ m) / self.r2_max

    def unproject(self, col, row):
        m = self.dist.undistort(self.plane(col, row))
        r2 = float(m @ m)
        if r2 >= self.r2_max or self.dist.valid_margin(m) <= 0.0:
            return None
        # The point of the unit sphere whose projection from (0, 0, -xi) is m.
        k = (self.xi + math.sqrt(1.0 + (1.0 - self.xi ** 2) * r2)) / (1.0 + r2)
        return unit([k * m[0], k * m[1], k - self.xi])


class KannalaBrandt4(Model):
    def __init__(self, fx, fy, cx, cy, k, max_fov_deg=None):
        self.fx, self.fy, self.cx, self.cy, self.k = fx, fy, cx, cy, k
        if max_fov_deg is None:
            # The crate's documented default: the smaller of 125 degrees and
            # the first angle where theta_d stops increasing.
            k1, k2, k3, k4 = k
            roots = np.roots([9.0 * k4, 7.0 * k3, 5.0 * k2, 3.0 * k1, 1.0])
            real = [math.sqrt(r.real) for r in roots if abs(r.imag) < 1e-12 and r.real > 0.0]
            self.half_fov = min([math.radians(125.0)] + real)
        else:
            self.half_fov = math.radians(max_fov_deg) / 2.0
        assert all(self.d_prime(t) > 0.0 for t in np.linspace(0.0, self.half_fov, 10001))

    def d(self, theta):
        k1, k2, k3, k4 = self.k
        t2 = theta * theta
        return theta * (1.0 + k1 * t2 + k2 * t2 ** 2 + k3 * t2 ** 3 + k4 * t2 ** 4)

    def d_prime(self, theta):
        k1, k2, k3, k4 = self.k
        t2 = theta * theta
        return 1.0 + 3.0 * k1 * t2 + 5.0 * k2 * t2 ** 2 + 7.0 * k3 * t2 ** 3 + 9.0 * k4 * t2 ** 4

    radius = d

    def domain_margin(self, p):
        return self.half_fov - math.atan2(math.hypot(p[0], p[1]), p[2])

    def project(self, p):
        r = math.hypot(p[0], p[1])
        if (r == 0.0 and not p[2] > 0.0) or math.atan2(r, p[2]) > self.half_fov:
            return None
        if r == 0.0:
            return self.pixel(0.0, 0.0)
        s = self.d(math.atan2(r, p[2])) / r
        return self.pixel(s * p[0], s * p[1])

    def pixel_margin(self, col, row):
        mx, my = self.plane(col, row)
        return 1.0 - math.hypot(mx, my) / self.d(self.half_fov)

    def unproject(self, col, row):
        mx, my = self.plane(col, row)
        r = math.hypot(mx, my)
        if r == 0.0:
            return np.array([0.0, 0.0, 1.0])
        if r > self.d(self.half_fov):
            return None
        theta = min(r, self.half_fov)
        for _ in range(100):
            step = (self.d(theta) - r) / self.d_prime(theta)
            theta -= step
            if abs(step) <= 1e-14 * max(theta, 1e-300):
                break
        else:
            raise RuntimeError(f"theta did not converge for r = {r}")
        assert abs(self.d(theta) - r) <= 1e-14 * r
        s = math.sin(theta) / r
        return np.array([s * mx, s * my, math.cos(theta)])


class PinholeRadtan(Model):
    def __init__(self, fx, fy, cx, cy, distortion):
        self.fx, self.fy, self.cx, self.cy, self.dist = fx, fy, cx, cy, distortion
        self.radial = distortion.p1 == 0.0 and distortion.p2 == 0.0
        fold = distortion.fold_r2()
        self.half_fov = math.atan(math.sqrt(fold)) if math.isfinite(fold) else math.pi / 2.0
        # The largest distorted radius of the one-to-one domain, sampled.
        r_max = math.sqrt(fold) if math.isfinite(fold) else math.inf
        self.reach = math.inf
        if math.isfinite(r_max):
            self.reach = max(
                np.linalg.norm(distortion.distort(r * np.array([math.cos(a), math.sin(a)])))
                for r in np.linspace(0.0, r_max, 400)
                for a in np.linspace(0.0, 2.0 * math.pi, 360)
            )

    def domain_margin(self, p):
        theta = math.atan2(math.hypot(p[0], p[1]), p[2])
        if theta >= math.pi / 2.0:
            return math.pi / 2.0 - theta
        return min(math.pi / 2.0 - theta, self.dist.valid_margin(np.array([p[0] / p[2], p[1] / p[2]])))

    def project(self, p):
        if not p[2] > 0.0:
            return None
        m = np.array([p[0] / p[2], p[1] / p[2]])
        if self.dist.valid_margin(m) <= 0.0:
            return None
        return self.pixel(*self.dist.distort(m))

    def radius(self, theta):
        return float(self.dist.distort(np.array([math.tan(theta), 0.0]))[0])

    def pixel_margin(self, col, row):
        # Outside only beyond the reach of the whole one-to-one domain.
        r = math.hypot(*self.plane(col, row))
        if r > 1.02 * self.reach:
            return -1.0
        m = self.dist.undistort(self.plane(col, row))
        return self.dist.valid_margin(m)

    def unproject(self, col, row):
        if math.hypot(*self.plane(col, row)) > self.reach:
            return None
        m = self.dist.undistort(self.plane(col, row))
        if self.dist.valid_margin(m) <= 0.0:
            return None
        return unit([m[0], m[1], 1.0])


# --------------------------------------------------------------------------
# Cameras: (name, model name, intrinsics, distortion or None, max_fov or None,
# image_size [height, width]).
# --------------------------------------------------------------------------
CAMERAS = [
    ("ds-tumvi-512", "ds",
     [190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504, -0.18, 0.59],
     None, None, [512, 512]),
    ("ds-1216", "ds", [262.3, 262.1, 607.8, 608.3, -0.2, 0.6], None, None, [1216, 1216]),
    ("ds-alpha-below-half", "ds", [320.5, 319.8, 511.2, 508.7, 0.45, 0.35], None, None, [1024, 1024]),
    ("eucm-tumvi-512", "eucm",
     [191.14799816648748, 191.13150946585135, 254.95857715233118, 256.8815466235898,
      0.6291060871161842, 1.0418067403139693],
     None, None, [512, 512]),
    ("eucm-alpha-below-half", "eucm", [410.0, 409.5, 639.5, 479.5, 0.42, 0.85], None, None, [960, 1280]),
    ("ucm-xi-below-one", "ucm", [300.0, 301.0, 319.5, 239.5, 0.8], None, None, [480, 640]),
    ("ucm-xi-above-one", "ucm", [820.0, 820.0, 511.5, 511.5, 2.2], None, None, [1024, 1024]),
    ("ucm-radtan", "ucm", [760.0, 758.5, 640.2, 480.7, 1.4], [-0.25, 0.06, 0.0005, -0.0003], None,
     [960, 1280]),
    ("kb4-240", "kb4", [280.0, 280.3, 607.5, 607.9], [0.0246, -0.0062, 0.00081, -0.00004], 240.0,
     [1216, 1216]),
    ("kb4-tumvi-512", "kb4",
     [190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504],
     [0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202, 0.00020293673591811182],
     None, [512, 512]),
    ("pinhole-radtan-euroc", "pinhole-radtan", [458.654, 457.296, 367.215, 248.375],
     [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05], None, [480, 752]),
    ("pinhole-radtan-fold", "pinhole-radtan", [400.0, 401.0, 319.5, 239.5],
     [-0.4, 0.05, 0.001, -0.0008], None, [480, 640]),
]


def build(model, intr, dist, max_fov):
    if model == "ds":
        return DoubleSphere(*intr)
    if model == "eucm":
        return ExtendedUnified(*intr)
    if model == "ucm":
        return Unified(*intr, RadTan(*dist) if dist else NO_DISTORTION)
    if model == "kb4":
        return KannalaBrandt4(*intr, dist, max_fov)
    if model == "pinhole-radtan":
        return PinholeRadtan(*intr, RadTan(*dist))
    raise ValueError(model)


def rounded(v, digits=9):
    return [float(f"{x:.{digits}g}") for x in v]


def golden_points(cam, rng):
    """Points inside the domain (also just inside its edge) and outside it."""
    half = cam.half_fov
    # A pinhole without a fold sees up to 90 degrees, where |m| is unbounded:
    # sample its inside up to 80 degrees.
    sample_half = min(half, math.radians(80.0)) if isinstance(cam, PinholeRadtan) else half
    inside = [0.0, 0.2, 0.45, 0.7, 0.9, 0.98, 0.999]
    if sample_half == half:
        inside.append(1.0 - 1e-5)
    points = []
    for i, frac in enumerate(inside):
        for j in range(3):
            theta = frac * sample_half
            az = 0.3 + 2.1 * j + 0.7 * i
            depth = float(rng.uniform(0.3, 30.0))
            points.append(depth * np.array(
                [math.sin(theta) * math.cos(az), math.sin(theta) * math.sin(az), math.cos(theta)]))
    for theta, az in [(half + 2e-3, 1.0), (half + 0.3, 4.0)]:
        if theta < math.pi:
            points.append(2.0 * np.array(
                [math.sin(theta) * math.cos(az), math.sin(theta) * math.sin(az), math.cos(theta)]))
    points.append(np.array([0.0, 0.0, -1.5]))
    points.append(np.array([0.0, 0.0, 0.0]))
    if isinstance(cam, PinholeRadtan):
        points.append(np.array([1.0, -0.5, 0.0]))
    return [np.array(rounded(p)) for p in points]


def golden_pixels(cam, height, width):
    """A grid over the image, the principal point, and a radial line through
    the edge of the pixels that unproject."""
    pixels = [(cam.cx, cam.cy)]
    for r in np.linspace(0.0, height - 1.0, 5):
        for c in np.linspace(0.0, width - 1.0, 5):
            pixels.append((c + 0.25, r + 0.5))
    # The edge radius in the undistorted image plane, if any.
    if isinstance(cam, (DoubleSphere, ExtendedUnified)) and math.isfinite(cam.r2_max):
        edge = math.sqrt(cam.r2_max)
    elif isinstance(cam, Unified) and math.isfinite(cam.r2_max):
        edge = math.sqrt(cam.r2_max)
    elif isinstance(cam, KannalaBrandt4):
        edge = cam.d(cam.half_fov)
    elif isinstance(cam, PinholeRadtan) and math.isfinite(cam.reach):
        edge = None
        for s in [0.5, 0.99]:
            m = s * math.sqrt(cam.dist.fold_r2()) * np.array([math.cos(2.5), math.sin(2.5)])
            pixels.append(cam.pixel(*cam.dist.distort(m)))
        for s in [1.05, 1.5]:
            pixels.append(cam.pixel(s * cam.reach * math.cos(0.4), s * cam.reach * math.sin(0.4)))
    else:
        edge = None
    if isinstance(cam, DoubleSphere):
        # Both sides of the image of the paper's projection cone.
        cone = cam.radius(cam.half_fov)
        for s in [0.999, 1.001]:
            pixels.append(cam.pixel(s * cone * math.cos(2.0), s * cone * math.sin(2.0)))
    if edge is not None:
        direction = np.array([math.cos(0.8), math.sin(0.8)])
        for s in [0.5, 0.99, 0.9999, 1.0001, 1.02]:
            m = s * edge * direction
            if isinstance(cam, Unified):
                m = cam.dist.distort(m)
            pixels.append(cam.pixel(*m))
    return [tuple(rounded(px, 12)) for px in pixels]


def main():
    rng = np.random.default_rng(20240607)
    cameras = []
    for name, model, intr, dist, max_fov, size in CAMERAS:
        cam = build(model, intr, dist, max_fov)
        project = []
        for p in golden_points(cam, rng):
            # (The origin and, for a pinhole, a point of the plane z = 0 lie
            # outside by definition.)
            if p[2] != 0.0:
                assert abs(cam.domain_margin(p)) > MARGIN, (name, p)
            px = cam.project(p)
            if px is not None:
                back = cam.unproject(*px)
                assert angle_between(back, p) < 1e-9, (name, p, back)
            project.append({"point": list(p), "pixel": None if px is None else list(px)})
        unproject = []
        for col, row in golden_pixels(cam, *size):
            if not (col == cam.cx and row == cam.cy):
                assert abs(cam.pixel_margin(col, row)) > MARGIN, (name, col, row)
            ray = cam.unproject(col, row)
            entry = {"pixel": [col, row], "ray": None if ray is None else list(ray)}
            if ray is not None and cam.domain_margin(ray) < 0.0:
                # The double sphere paper's unprojection is defined on
                # r^2 <= 1 / (2 alpha - 1) (all pixels for alpha <= 0.5), but
                # for xi != 0 its projection cone z > -w2 |p| is narrower than
                # the image of that disc: these rays would not project back.
                assert cam.domain_margin(ray) < -MARGIN, (name, col, row)
                entry = {"pixel": [col, row], "ray": None, "formula_ray": list(ray)}
                ray = None
            if ray is not None:
                assert cam.domain_margin(ray) > MARGIN or (col == cam.cx and row == cam.cy)
                assert abs(np.linalg.norm(ray) - 1.0) < 1e-15
                back = cam.project(ray)
                scale = max(1.0, math.hypot(col - cam.cx, row - cam.cy) / 1000.0)
                assert math.hypot(back[0] - col, back[1] - row) < 1e-9 * scale, (name, col, row)
                if cam.radial and not isinstance(cam, KannalaBrandt4):
                    by_angle = cam.unproject_by_bisection(col, row)
                    assert angle_between(by_angle, ray) < 1e-9, (name, col, row)
            unproject.append(entry)
        entry = {"name": name, "model": model, "intrinsics": intr}
        if dist is not None:
            entry["distortion"] = dist
        if max_fov is not None:
            entry["max_fov"] = max_fov
        entry["image_size"] = size
        entry["max_fov_deg"] = 2.0 * math.degrees(cam.half_fov)
        entry["project"] = project
        entry["unproject"] = unproject
        cameras.append(entry)
        n_null_p = sum(e["pixel"] is None for e in project)
        n_null_u = sum(e["ray"] is None for e in unproject)
        n_formula = sum("formula_ray" in e for e in unproject)
        print(f"{name}: fov {entry['max_fov_deg']:.4f} deg, {len(project)} points "
              f"({n_null_p} outside), {len(unproject)} pixels ({n_null_u} outside, {n_formula} of them by the cone)")
    write(cameras)


def write(cameras):
    """One JSON value per golden entry and line (small diffs, small file)."""
    header = {
        "generated_by": "scripts/camera_golden/make_camera_golden.py",
        "regenerate": "python3 scripts/camera_golden/make_camera_golden.py (from the repository root; numpy)",
        "conventions": "camera frame x right, y down, z forward; pixel [col, row], 0-based, "
                       "centres at integers; image_size [height, width]; null: outside the "
                       "model's domain; max_fov_deg: the model's full field of view; "
                       "formula_ray: the published closed-form unprojection of a pixel whose ray "
                       "lies outside the published projection domain (double sphere, xi != 0), "
                       "so that the pixel does not unproject",
    }
    lines = ["{"]
    for key, value in header.items():
        lines.append(f"  {json.dumps(key)}: {json.dumps(value)},")
    lines.append('  "cameras": [')
    for i, cam in enumerate(cameras):
        lines.append("    {")
        for key in ["name", "model", "intrinsics", "distortion", "max_fov", "image_size", "max_fov_deg"]:
            if key in cam:
                lines.append(f"      {json.dumps(key)}: {json.dumps(cam[key])},")
        for key in ["project", "unproject"]:
            lines.append(f"      {json.dumps(key)}: [")
            rows = [f"        {json.dumps(e)}" for e in cam[key]]
            lines.append(",\n".join(rows))
            lines.append("      ]" + ("," if key == "project" else ""))
        lines.append("    }" + ("," if i + 1 < len(cameras) else ""))
    lines.append("  ]")
    lines.append("}")
    text = "\n".join(lines) + "\n"
    json.loads(text)
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "w", encoding="utf-8") as f:
        f.write(text)
    print(f"wrote {OUT} ({len(text)} bytes)")


if __name__ == "__main__":
    main()
