#!/usr/bin/env python3
"""Where a network loses to ZNCC+SGM on held-out frames: the share of pixels off by more than 3 %
(the reference's >3) and the MAE of both, by distance to the nearest depth edge of the ground
truth (an edge: a neighbouring pixel whose index differs by more than 3 % of N), at 160x640 with
the reference's rules (omni_np.py's scoring, sky not scored). Pixels of all frames pooled.

Usage: error_by_edge_distance.py DATASET NET_OUT SGM_OUT FIRST LAST
e.g.   error_by_edge_distance.py /work/data/test-things-s7001 /work/eval/c14e16-test-things-s7001 \
           /work/eval/sgm-test-things-s7001 1 20
"""
import os
import sys

import numpy as np
import scipy.ndimage as nd

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "../../../../shared/tools"))
import omni_np as O  # noqa: E402

ds, net_dir, sgm_dir, first, last = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
_, _, min_depth = O.load(ds)
bins = [0, 2, 4, 8, 16, 100000]
acc = {i: np.zeros(5) for i in range(len(bins) - 1)}


def pred(d, f):
    return O.upsample(O.read_f32_tiff(f"{d}/{f:05d}.tiff"), 160, 640)


for f in range(first, last + 1):
    gt = O.gt_reference(ds, f, 160, 640, 45.0)
    gi, valid, min_inv, step = O.reference_gt_index(gt, min_depth)
    e_net = np.abs((pred(net_dir, f) - min_inv) / step - gi) / 192 * 100
    e_sgm = np.abs((pred(sgm_dir, f) - min_inv) / step - gi) / 192 * 100
    g = np.where(gi < 0, 0, gi)
    gx = np.abs(np.roll(g, -1, 1) - g)
    gy = np.abs(np.diff(g, axis=0, append=g[-1:]))
    edge = (gx > 0.03 * 192) | (gy > 0.03 * 192)
    dist = nd.distance_transform_edt(~edge)
    for i in range(len(bins) - 1):
        m = valid & (dist >= bins[i]) & (dist < bins[i + 1])
        acc[i] += [m.sum(), (e_net[m] > 3).sum(), (e_sgm[m] > 3).sum(), e_net[m].sum(), e_sgm[m].sum()]

total = sum(a[0] for a in acc.values())
print("distance to an edge | share of pixels | net >3 % | SGM >3 % | net MAE | SGM MAE")
for i, a in acc.items():
    n = a[0]
    print(f"{bins[i]}-{bins[i + 1]} px | {n / total * 100:.1f} % | {a[1] / n * 100:.1f} | "
          f"{a[2] / n * 100:.1f} | {a[3] / n:.2f} | {a[4] / n:.2f}")
