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
from studylib import block_span, index_scale, o  # noqa: E402

ds, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
_, _, md = o.load(ds)
min_inv, step = index_scale(md)
res = {4: [], 2: []}
for f in range(a, b + 1):
    g = (o.gt_for_output(ds, f, 160, 640, 45.0) - min_inv) / step
    for s in res:
        h, w = 160 // s, 640 // s
        centre_rows = np.round(np.arange(h) * 159 / (h - 1)).astype(int)
        not_sky = g[centre_rows][:, (np.arange(w) * s) % 640] > 0
        res[s].append((block_span(g, s) > 6)[not_sky])
for s, v in res.items():
    print(f"{ds} {a}-{b}: {160 // s} x {640 // s} grid, {s} x {s} blocks: "
          f"{100 * np.concatenate(v).mean():.1f} % of the non-sky pixels cover a depth edge")
