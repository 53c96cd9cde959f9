#!/usr/bin/env python3
"""Same-run reference timing for the lookup-table build: the full table
(4 cameras, 160x640, N=192, every other sphere) built the way the reference
Python implementation does it (numpy, vectorised over pixels, a loop over
spheres and cameras, float64), from FORMATS.md.

    python3 scripts/bench_lut_numpy.py ../shared/data/omnimvs-samples/sunny_single/config.yaml
"""
import sys
import time

import numpy as np
import yaml

sys.path.insert(0, __file__.rsplit("/", 1)[0] + "/lut_golden")
from make_lut_golden import rodrigues, world2cam  # noqa: E402

H, W, PHI, N = 160, 640, 45.0, 192
EPS = np.finfo(np.float64).eps


def build(cfg):
    cc, rr = np.meshgrid(np.arange(W), np.arange(H))
    theta = (cc - W / 2) / (W / 2) * np.pi + np.pi / 2
    phi = (rr - (H - 1) / 2) / ((H - 1) / 2) * np.deg2rad(PHI)
    rays = np.stack([-np.cos(phi) * np.cos(theta), np.sin(phi), np.cos(phi) * np.sin(theta)]).reshape(3, -1)
    d1 = 1.0 / cfg["config"]["omnimvs_sweep_min_depth"]
    inv = EPS + np.arange(N) * (d1 - EPS) / (N - 1)
    cams = cfg["cameras"]
    out = np.zeros((len(cams), N // 2, H, W, 2), np.float32)
    poses = [(rodrigues(np.asarray(c["pose"][:3], float)), np.asarray(c["pose"][3:], float).reshape(3, 1)) for c in cams]
    for k in range(N // 2):
        pts = rays / inv[2 * k]
        for i, cam in enumerate(cams):
            R, t = poses[i]
            col, row, ok = world2cam(cam, R.T @ (pts - t))
            col = np.where(ok, col, -1.0)
            row = np.where(ok, row, -1.0)
            col[col < 0] = -1e5
            row[row < 0] = -1e5
            h, w = cam["image_size"]
            out[i, k, :, :, 0] = (col / (w - 1) * 2 - 1).reshape(H, W)
            out[i, k, :, :, 1] = (row / (h - 1) * 2 - 1).reshape(H, W)
    return out


def main():
    cfg = yaml.safe_load(open(sys.argv[1]))
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        build(cfg)
        times.append(time.perf_counter() - t0)
    print(f"numpy reference-style LUT build: best {min(times):.2f} s, runs {[round(t, 2) for t in times]}")


if __name__ == "__main__":
    main()
