#!/usr/bin/env python3
"""Seeds for `--example cascade_seeded` that say how good the coarse stage has to be: the
truth at the coarse grid (40 x 160, nearest sample of the ground truth, inverse depth in 1/m),
or the network's own coarse answer (from a `cascade_dump`) with the truth put in where the
answer is more than T index units off (all of them, or a random share P of them). Also prints,
for the non-sky coarse pixels, how many are more than 20 off and whether the ground truth's
4 x 4 output pixels around the coarse pixel's centre hold a depth edge (span over 6 index units).

    python3 coarse_seeds.py DATASET DUMP_DIR A B OUT_DIR [T [P]]   (no T: the truth alone)
"""
import os
import sys

import numpy as np
import tifffile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import block_span, index_scale, o  # noqa: E402

ds, dump, a, b, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
T = float(sys.argv[6]) if len(sys.argv) > 6 else None
P = float(sys.argv[7]) if len(sys.argv) > 7 else 1.0
_, _, md = o.load(ds)
min_inv, step = index_scale(md)
rng = np.random.default_rng(5)
os.makedirs(out, exist_ok=True)
fixed, stats = [], []
for f in range(a, b + 1):
    truth = o.gt_for_output(ds, f, 40, 160, 45.0)
    own = np.fromfile(f"{dump}/{f:05d}_coarse.f32", "<f4").reshape(40, 160)
    gidx = (truth - min_inv) / step
    if T is None:
        seed = truth
    else:
        fix = (np.abs(own - gidx) > T) & (rng.random(own.shape) < P)
        fixed.append(fix.mean())
        seed = np.where(fix, truth, min_inv + own * step)
    tifffile.imwrite(f"{out}/{f:05d}.tiff", seed.astype(np.float32))
    full = (o.gt_for_output(ds, f, 160, 640, 45.0) - min_inv) / step
    span = block_span(full, 4)
    stats.append(np.stack([np.abs(own - gidx).ravel(), span.ravel(), (gidx > 0).ravel()]))
if fixed:
    print(f"{out}: truth put in at {100 * np.mean(fixed):.1f} % of the coarse pixels")
err, span, ok = np.concatenate(stats, 1)
ok = ok > 0.5
gross = ok & (err > 20)
edge = span > 6
print(f"{ds} {a}-{b}: non-sky coarse pixels more than 20 off: {100 * gross.sum() / ok.sum():.1f} %; "
      f"{100 * (gross & edge).sum() / gross.sum():.1f} % of them hold a depth edge in their 4 x 4 "
      f"block ({100 * (ok & edge).sum() / ok.sum():.1f} % of all pixels do; of those "
      f"{100 * (gross & edge).sum() / (ok & edge).sum():.1f} % are more than 20 off, of the others "
      f"{100 * (gross & ~edge).sum() / (ok & ~edge).sum():.1f} %)")
