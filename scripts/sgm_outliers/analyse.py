#!/usr/bin/env python3
"""Where the large errors of a depth method come from (the outlier study of `research/learned-costs.md`).

Every pixel the reference rules score (160x640, N = 192, sky not scored) is put in the first
class it belongs to:

  seen<2  fewer than two cameras see its ground-truth point (field of view and image bounds)
  far     distant background: ground-truth index below 8 (beyond 24x the minimum depth)
  edge    within 2 pixels of an occlusion edge (ground-truth index jump > 8 between neighbours)
  flat    textureless: the 9x9 standard deviation of the cameras' mean gray value, sampled at
          the ground-truth point, below 4 gray levels
  other   everything else

and the table gives, per class: its share of the scored pixels, its share of the pixels with
an error over 3 % of N (">3"), and its part of the MAE (its errors summed over all scored
pixels, so the parts add up to the MAE).

Usage: analyse.py DATASET OUTDIR A B [OUTDIR2 ...]   (frames A..B; outputs OUTDIR/%05d.tiff)
Uses ../../../shared/tools/omni_np.py (numpy, scipy, tifffile, pyyaml, pillow).
"""
import os
import sys

import numpy as np
import scipy.ndimage

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "shared", "tools"))
import omni_np as on  # noqa: E402

CLASSES = ["seen<2", "far", "edge", "flat", "other"]


def classes(ds, frame, gt_inv, phi_deg=45.0):
    cfg, cams, min_depth = on.load(ds)
    gt_idx, valid, _, _ = on.reference_gt_index(gt_inv, min_depth)
    h, w = gt_inv.shape
    R = on.rays(h, w, phi_deg)
    d = np.maximum(gt_inv.reshape(-1), 1e-6)
    X = R / d
    seen = np.zeros(h * w, int)
    total = np.zeros(h * w)
    count = np.zeros(h * w)
    for i, c in enumerate(cams):
        im = on.read_gray(on.frame_path(ds, i, cfg, frame))
        col, row, ok_fov = c.project(X)
        v, ok = on.bilinear(im, col, row)
        ok &= ok_fov
        seen += ok
        total += np.where(ok, v, 0)
        count += ok
    mean = (total / np.maximum(count, 1)).reshape(h, w)
    # 9x9 standard deviation, longitude wraps.
    m1 = scipy.ndimage.uniform_filter(mean, 9, mode=["nearest", "wrap"])
    m2 = scipy.ndimage.uniform_filter(mean ** 2, 9, mode=["nearest", "wrap"])
    std = np.sqrt(np.maximum(m2 - m1 ** 2, 0))
    jump = np.zeros((h, w), bool)
    g = np.where(valid, gt_idx, 0)
    jump[:, :] |= np.abs(g - np.roll(g, 1, axis=1)) > 8
    jump[1:, :] |= np.abs(g[1:] - g[:-1]) > 8
    edge = scipy.ndimage.binary_dilation(jump, np.ones((5, 5), bool))
    cls = np.full((h, w), 4)
    cls[(std < 4)] = 3
    cls[edge] = 2
    cls[gt_idx < 8] = 1
    cls[seen.reshape(h, w) < 2] = 0
    return cls, gt_idx, valid, min_depth


def main():
    ds, a, b = sys.argv[1], int(sys.argv[3]), int(sys.argv[4])
    outdirs = [sys.argv[2]] + sys.argv[5:]
    n = 192
    for outdir in outdirs:
        share = np.zeros(5)
        big = np.zeros(5)
        err = np.zeros(5)
        scored = 0
        for f in range(a, b + 1):
            pred = on.read_f32_tiff(os.path.join(outdir, f"{f:05d}.tiff"))
            gt = on.gt_reference(ds, f, 160, 640, 45.0)
            cls, gt_idx, valid, min_depth = classes(ds, f, gt)
            min_inv, step = 1.0 / (1.0 / on.EPS), (1.0 / min_depth - 1.0 / (1.0 / on.EPS)) / (n - 1)
            pred_idx = (pred - min_inv) / step
            e = np.abs(pred_idx - gt_idx) / n * 100
            for k in range(5):
                m = valid & (cls == k)
                share[k] += m.sum()
                big[k] += (e[m] > 3).sum()
                err[k] += e[m].sum()
            scored += valid.sum()
        print(f"\n{outdir} (frames {a}..{b}): MAE {err.sum() / scored:.2f}, >3 {big.sum() / scored * 100:.2f} %")
        print("| class | pixels (%) | of the >3 pixels (%) | >3 within the class (%) | part of the MAE |")
        print("|---|---:|---:|---:|---:|")
        for k, name in enumerate(CLASSES):
            print(f"| {name} | {share[k] / scored * 100:.1f} | {big[k] / max(big.sum(), 1) * 100:.1f} | "
                  f"{big[k] / max(share[k], 1) * 100:.1f} | {err[k] / scored:.2f} |")


if __name__ == "__main__":
    main()
