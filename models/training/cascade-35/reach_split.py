#!/usr/bin/env python3
"""Which pixels carry the error: split by distance to a depth edge of the truth and by how far
the full stage's nearest evenly spaced hypothesis is from the truth (within 1: a miss the stage
could fix; beyond 5: a gross miss made before it). Then, for the gross misses, whether an earlier
stage's answers around the pixel held the truth: the best of the coarse answers over the 3 x 3
and 5 x 5 coarse pixels around its parent, within 5 and within the half stage's reach (8.75).
Reads a `cascade_dump`.

    python3 reach_split.py DUMP_DIR A B
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import dump_frame, edge_distance  # noqa: E402

d, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
acc = []
for f in range(a, b + 1):
    shapes, get = dump_frame(d, f)
    gt, valid = get("gt"), get("valid") > 0.5
    ok = valid & (gt > 0)
    hyp, full, coarse = get("full_hyp"), get("full"), get("coarse")
    ke = shapes.get("full_even", len(hyp))
    even_best = np.abs(hyp[:ke] - gt[None]).min(0)
    dist = edge_distance(gt, valid)
    best = {}
    for r in (1, 2):
        m = np.full(gt.shape, np.inf)
        for dy in range(-r, r + 1):
            rows = np.clip(np.arange(coarse.shape[0]) + dy, 0, coarse.shape[0] - 1)
            for dx in range(-r, r + 1):
                s = np.roll(coarse[rows], -dx, axis=1)
                m = np.minimum(m, np.abs(np.kron(s, np.ones((4, 4))) - gt))
        best[r] = m
    acc.append(np.stack([np.abs(full - gt)[ok], even_best[ok], dist[ok], best[1][ok], best[2][ok]]))
e, eb, dist, b3, b5 = np.concatenate(acc, 1)
total = e.sum()
print(f"{d}, frames {a}-{b}: MAE {e.mean():.3f}")
for name, m0 in (("near", dist < 4), ("mid", (dist >= 4) & (dist < 16)), ("far", dist >= 16)):
    for rn, r in (("in reach (a hypothesis within 1)", eb <= 1), ("1-5", (eb > 1) & (eb <= 5)),
                  ("beyond 5", eb > 5)):
        m = m0 & r
        print(f"  {name:4} {rn:33} share {100 * m.mean():5.1f} %  MAE {e[m].mean():6.2f}  "
              f"share of the summed error {100 * e[m].sum() / total:5.1f} %")
g = eb > 5
print(f"  gross misses (beyond 5): {100 * g.mean():.1f} % of the pixels, "
      f"{100 * e[g].sum() / total:.1f} % of the summed error; the truth within 5 / 8.75 of a coarse "
      f"answer around the parent: 3x3 {100 * (b3[g] <= 5).mean():.1f} / {100 * (b3[g] <= 8.75).mean():.1f} %, "
      f"5x5 {100 * (b5[g] <= 5).mean():.1f} / {100 * (b5[g] <= 8.75).mean():.1f} %")
