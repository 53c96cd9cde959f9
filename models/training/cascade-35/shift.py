#!/usr/bin/env python3
# Is the answer registered with the truth? MAE of the full-resolution answer shifted by
# (dy, dx) output pixels against the truth (columns wrap, rows clamp); the coarse and half
# answers repeated onto the output grid (so their best shift is about -1.5 and -0.5 columns).
# Usage: shift.py DUMP_DIR A B [full|half|coarse]
import os
import sys
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import dump_frame  # noqa: E402
d, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
key = sys.argv[4] if len(sys.argv) > 4 else "full"
res = {}
for f in range(a, b + 1):
    shapes, get = dump_frame(d, f)
    gt, valid = get("gt"), get("valid") > 0.5
    ok = valid & (gt > 0)
    p = get(key)
    H, W = gt.shape
    if p.shape != gt.shape:
        s = H // p.shape[0]
        p = np.kron(p, np.ones((s, s)))
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            rows = np.clip(np.arange(H) - dy, 0, H - 1)
            q = np.roll(p[rows], dx, axis=1)
            e = np.abs(q - gt)[ok]
            res.setdefault((dy, dx), []).append(e)
base = np.concatenate(res[(0, 0)]).mean()
print(f"{key}: MAE unshifted {base:.3f}")
for dy in range(-2, 3):
    print("  " + "  ".join(f"({dy:+d},{dx:+d}) {np.concatenate(res[(dy, dx)]).mean():6.3f}" for dx in range(-2, 3)))
