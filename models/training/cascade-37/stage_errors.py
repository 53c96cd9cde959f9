#!/usr/bin/env python3
"""Each stage's error against the truth, for dumps of networks whose coarse stage sits on
either grid (40 x 160 or 80 x 320): every stage's index map repeated up to the output grid
(160 x 640, nearest), scored on valid non-sky pixels of the training ground truth (index
units of N = 192): MAE, and the share of pixels missed by more than 5, 10 (the half stage's
reach is 8.75) and 20. Also the coarse answer's misses split by whether the pixel's
block of the 40 x 160 grid holds a depth edge of the truth (an index step over 10 inside its
4 x 4 output pixels; the same split for every network), and the
misses away from edges by the truth's depth (index bands: far to near).
Reads `cascade_dump` folders.

    python3 stage_errors.py A B DUMP_DIR...
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import dump_frame  # noqa: E402

a, b = int(sys.argv[1]), int(sys.argv[2])


def up(m, shape):
    fy, fx = shape[0] // m.shape[0], shape[1] // m.shape[1]
    return np.kron(m, np.ones((fy, fx), dtype=m.dtype))


def block_has_edge(gt, valid, f):
    """Per output pixel: whether its f x f block (of the grid f times coarser) spans over 10."""
    h, w = gt.shape
    g = np.where(valid, gt, np.nan).reshape(h // f, f, w // f, f)
    with np.errstate(all='ignore'):
        span = np.nanmax(g, axis=(1, 3)) - np.nanmin(g, axis=(1, 3))
    return up(np.nan_to_num(span) > 10, gt.shape)


for d in sys.argv[3:]:
    acc = {k: [] for k in ("coarse", "half", "full")}
    edge, truth = [], []
    for f in range(a, b + 1):
        shapes, get = dump_frame(d, f)
        gt, valid = get("gt"), get("valid") > 0.5
        ok = valid & (gt > 0)
        for k in acc:
            acc[k].append(np.abs(up(get(k), gt.shape) - gt)[ok])
        # The same split for every network: the 4 x 4 blocks of the 40 x 160 grid.
        edge.append(block_has_edge(gt, valid, 4)[ok])
        truth.append(gt[ok])
    print(f"{d} (coarse grid {shapes['coarse'][0]} x {shapes['coarse'][1]})")
    for k, v in acc.items():
        e = np.concatenate(v)
        print(f"  {k:6s} MAE {e.mean():6.2f}  >5 {100 * (e > 5).mean():5.1f} %  "
              f">10 {100 * (e > 10).mean():5.1f} %  >20 {100 * (e > 20).mean():5.1f} %")
    e, ed = np.concatenate(acc["coarse"]), np.concatenate(edge)
    print(f"  pixels whose 4 x 4 block holds an edge: {100 * ed.mean():.1f} %; of the misses "
          f"over 20, {100 * ed[e > 20].mean():.1f} % there; miss rate >20 there "
          f"{100 * (e[ed] > 20).mean():.1f} %, elsewhere {100 * (e[~ed] > 20).mean():.1f} %")
    t = np.concatenate(truth)
    bands = [(0, 10), (10, 30), (30, 60), (60, 100), (100, 192)]
    cells = []
    for lo, hi in bands:
        m = ~ed & (t > lo) & (t <= hi)
        cells.append(f"{lo}-{hi}: {100 * m.mean():4.1f} % of px, >20 {100 * (e[m] > 20).mean():4.1f} %")
    print("  away from edges, by true index: " + "; ".join(cells))
