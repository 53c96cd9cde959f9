#!/usr/bin/env python3
"""How often a grid pixel covers a depth edge: the share of the non-sky pixels of the 40 x 160
and 80 x 320 grids whose block of the 160 x 640 truth (4 x 4, 2 x 2 output pixels around its
centre) spans more than 6 index units.

    python3 edge_blocks.py DATASET A B
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o  # noqa: E402

ds, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
_, _, md = o.load(ds)
min_inv = 1.0 / (1.0 / o.EPS)
step = (1.0 / md - min_inv) / 191.0
res = {4: [], 2: []}
for f in range(a, b + 1):
    g = (o.gt_for_output(ds, f, 160, 640, 45.0) - min_inv) / step
    for s in res:
        h, w = 160 // s, 640 // s
        centre_rows = np.round(np.arange(h) * 159 / (h - 1)).astype(int)
        cols = (np.arange(w)[:, None] * s + np.arange(-s // 2, s // 2)[None, :]) % 640
        for r in range(h):
            rows = np.clip(np.arange(centre_rows[r] - s // 2, centre_rows[r] + s // 2), 0, 159)
            block = g[rows][:, cols]  # [s, w, s]
            span = block.max(axis=(0, 2)) - block.min(axis=(0, 2))
            res[s].append((span > 6)[g[centre_rows[r], (np.arange(w) * s) % 640] > 0])
for s, v in res.items():
    print(f"{ds} {a}-{b}: {160 // s} x {640 // s} grid, {s} x {s} blocks: "
          f"{100 * np.concatenate(v).mean():.1f} % of the non-sky pixels cover a depth edge")
