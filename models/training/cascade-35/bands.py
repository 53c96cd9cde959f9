#!/usr/bin/env python3
# Error and bias of the full answer by truth band and distance to an edge. Usage: bands.py DUMP_DIR A B
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
    full = get("full"); ok = valid & (gt > 0)
    dist = edge_distance(gt, valid)
    acc.append(np.stack([gt[ok], full[ok], dist[ok]]))
g, p, dist = np.concatenate(acc, 1)
e = p - g
print(f"all: MAE {np.abs(e).mean():.2f}, bias {e.mean():+.2f}")
for lo, hi in ((0, 20), (20, 40), (40, 80), (80, 120), (120, 193)):
    for name, m0 in (("all", dist >= 0), ("open(>=16)", dist >= 16), ("edge(<4)", dist < 4)):
        m = m0 & (g >= lo) & (g < hi)
        if m.sum() == 0: continue
        print(f"  truth {lo:3}-{hi:3} {name:10} share {100*m.mean():5.1f} %  MAE {np.abs(e[m]).mean():6.2f}  bias {e[m].mean():+6.2f}  median err {np.median(e[m]):+6.2f}  share of summed error {100*np.abs(e[m]).sum()/np.abs(e).sum():5.1f} %")
