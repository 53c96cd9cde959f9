#!/usr/bin/env python3
"""Where the error is, by truth band and distance to a depth edge of the truth, stage by stage
(the coarse and half answers repeated onto the output grid). Reads a `cascade_dump`.

    python3 stages_band.py DUMP_DIR A B
"""
import os
import sys
import numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import dump_frame, edge_distance
d, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
acc = []
for f in range(a, b + 1):
    shapes, get = dump_frame(d, f)
    gt, valid = get("gt"), get("valid") > 0.5
    ok = valid & (gt > 0)
    up = lambda m: np.kron(m, np.ones((gt.shape[0] // m.shape[0], gt.shape[1] // m.shape[1])))
    c, h, fu = up(get("coarse")), up(get("half")), get("full")
    dist = edge_distance(gt, valid)
    acc.append(np.stack([gt[ok], c[ok], h[ok], fu[ok], dist[ok]]))
g, c, h, fu, dist = np.concatenate(acc, 1)
for lo, hi in ((0, 40), (40, 80), (80, 120), (120, 193)):
    for name, m0 in (("open(>=16)", dist >= 16), ("mid", (dist >= 4) & (dist < 16)), ("edge(<4)", dist < 4)):
        m = m0 & (g >= lo) & (g < hi)
        print(f"truth {lo:3}-{hi:3} {name:10} share {100*m.mean():5.1f} %  MAE coarse {np.abs(c-g)[m].mean():6.2f} half {np.abs(h-g)[m].mean():6.2f} full {np.abs(fu-g)[m].mean():6.2f}   >10 off: coarse {100*(np.abs(c-g)[m]>10).mean():5.1f} % full {100*(np.abs(fu-g)[m]>10).mean():5.1f} %")
