#!/usr/bin/env python3
"""Each stage's signed error by the truth's depth: for `cascade_dump` folders, every stage's
index map repeated up to 160 x 640 (nearest) against the training ground truth, on valid
non-sky pixels, in bands of the true index (far to near, N = 192 units): the share of pixels,
and per stage the MAE and the mean signed error (negative: answered too far).

    python3 stage_bias.py A B DUMP_DIR...
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import dump_frame  # noqa: E402

BANDS = [(0, 30), (30, 60), (60, 100), (100, 130), (130, 160), (160, 175), (175, 192)]


def up(m, shape):
    fy, fx = shape[0] // m.shape[0], shape[1] // m.shape[1]
    return np.kron(m, np.ones((fy, fx), dtype=m.dtype))


a, b = int(sys.argv[1]), int(sys.argv[2])
for d in sys.argv[3:]:
    err = {k: [] for k in ("coarse", "half", "full")}
    truth = []
    for f in range(a, b + 1):
        _, get = dump_frame(d, f)
        gt, valid = get("gt"), get("valid") > 0.5
        ok = valid & (gt > 0)
        for k in err:
            err[k].append((up(get(k), gt.shape) - gt)[ok])
        truth.append(gt[ok])
    t = np.concatenate(truth)
    e = {k: np.concatenate(v) for k, v in err.items()}
    print(d)
    for lo, hi in BANDS:
        m = (t > lo) & (t <= hi)
        cells = "  ".join(f"{k} {np.abs(v[m]).mean():5.2f} {v[m].mean():+6.2f}" for k, v in e.items())
        print(f"  true {lo:3d}-{hi:3d} {100 * m.mean():5.1f} % px  {cells}")
