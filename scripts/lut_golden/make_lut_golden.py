#!/usr/bin/env python3
"""Independent golden values for the spherical-sweep lookup table.

Written from the conventions of the file formats chapter of the user guide (`docs/book/src/formats.md`) alone (numpy, no
code shared with the Rust implementation). For each sample rig it evaluates,
at a strided subset of the 160x640 (+-45 deg) grid and for a few spheres of
N = 192 (every other sphere, as in the `.hwd` file), the source pixel
(col, row) in every camera, or NaN where the entry is invalid (outside the
FOV, or a negative coordinate, which the reference replaces by -1e5).

Usage (from the repository root):
    python3 scripts/lut_golden/make_lut_golden.py ../shared/data/omnimvs-samples \
        crates/omnimvs-sweep/tests/golden

Output per sample: `<name>.json` (parameters) and `<name>.f32` (float32 LE,
shape [cameras, spheres, rows, cols, 2], pixel units, NaN = invalid).
"""
import json
import os
import sys

import numpy as np
import yaml

H, W, PHI_DEG, NDEPTH = 160, 640, 45.0, 192
ROW_STEP, COL_STEP = 8, 16
# Sphere k of the file is hypothesis n = 2k; 0 is the sphere at infinity.
SPHERES = [0, 1, 30, 95]
EPS = np.finfo(np.float64).eps


def rodrigues(r):
    theta = np.linalg.norm(r)
    if theta < 1e-300:
        return np.eye(3)
    k = r / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx


def world2cam(cam, p):
    """FORMATS.md world2cam; p is 3xM in camera coordinates -> (col, row, in_fov)."""
    X, Y, Z = p
    n = np.sqrt(X**2 + Y**2) + EPS
    theta = np.arctan2(-Z, n)
    inv = np.asarray(cam["inv_poly"][1:], dtype=np.float64)
    rho = np.polynomial.polynomial.polyval(theta, inv)
    x = Y / n * rho
    y = X / n * rho
    c, d, e = cam["affine"]
    xc, yc = cam["center"]
    row = c * x + d * y + xc
    col = e * x + y + yc
    in_fov = theta + np.pi / 2 <= np.deg2rad(cam["max_fov"]) / 2
    return col, row, in_fov


def main():
    samples, out_dir = sys.argv[1], sys.argv[2]
    rows = np.arange(0, H, ROW_STEP)
    cols = np.arange(0, W, COL_STEP)
    cc, rr = np.meshgrid(cols, rows)
    theta = (cc - W / 2) / (W / 2) * np.pi + np.pi / 2
    phi = (rr - (H - 1) / 2) / ((H - 1) / 2) * np.deg2rad(PHI_DEG)
    rays = np.stack([-np.cos(phi) * np.cos(theta), np.sin(phi), np.cos(phi) * np.sin(theta)]).reshape(3, -1)
    for name in ["sunny_single", "itbt_sample"]:
        cfg = yaml.safe_load(open(os.path.join(samples, name, "config.yaml")))
        min_depth = float(cfg["config"]["omnimvs_sweep_min_depth"])
        d0, d1 = EPS, 1.0 / min_depth
        inv_depths = d0 + np.arange(NDEPTH) * (d1 - d0) / (NDEPTH - 1)
        out = np.full((len(cfg["cameras"]), len(SPHERES), len(rows), len(cols), 2), np.nan)
        for ci, cam in enumerate(cfg["cameras"]):
            R = rodrigues(np.asarray(cam["pose"][:3], dtype=np.float64))
            t = np.asarray(cam["pose"][3:], dtype=np.float64).reshape(3, 1)
            for si, k in enumerate(SPHERES):
                pts = rays / inv_depths[2 * k]
                p_cam = R.T @ (pts - t)
                col, row, ok = world2cam(cam, p_cam)
                ok = ok & (col >= 0) & (row >= 0)
                col = np.where(ok, col, np.nan)
                row = np.where(ok, row, np.nan)
                out[ci, si, :, :, 0] = col.reshape(len(rows), len(cols))
                out[ci, si, :, :, 1] = row.reshape(len(rows), len(cols))
        out.astype("<f4").tofile(os.path.join(out_dir, name + ".f32"))
        meta = {
            "height": H, "width": W, "phi_deg": PHI_DEG, "ndepth": NDEPTH,
            "row_step": ROW_STEP, "col_step": COL_STEP, "spheres": SPHERES,
            "shape": list(out.shape),
            "invalid_entries": int(np.isnan(out[..., 0]).sum()),
        }
        json.dump(meta, open(os.path.join(out_dir, name + ".json"), "w"), indent=1)
        print(name, meta)


if __name__ == "__main__":
    main()
