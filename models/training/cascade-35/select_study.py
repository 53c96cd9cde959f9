#!/usr/bin/env python3
"""Could the four images choose, at a gross miss, which of the coarse answers around a pixel is
its surface? For the pixels whose full-stage hypotheses are all more than 5 index units from the
truth (85 % of the error, `reach_split.py`), the candidates are the coarse answers of the 3 x 3
coarse pixels around the pixel's nearest coarse pixel (what the half grid's learnt upsampling
chooses from); each is scored by the colours of the 3 x 3 panorama pixels around at its depth in
the cameras that see them (ZNCC over 27 values, images standardised): the mean over the camera
pairs, or the best pair. Prints the MAE of the network's answer, of each rule's pick and of the
best candidate (oracle), and how often the pick is within 5 of the truth.

    python3 select_study.py DUMP_DIR DATASET A B
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import (dump_frame, index_scale, o, pair_costs, patch_colours,  # noqa: E402
                      standardised_images)

d, ds, a, b = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
cfg, cams, md = o.load(ds)
H, W = 160, 640
R = o.rays(H, W, 45.0).reshape(3, H, W)
min_inv, step = index_scale(md)
out = {k: [] for k in ('ans', 'oracle', 'mean', 'min', 'bilinear_like')}
for f in range(a, b + 1):
    shapes, get = dump_frame(d, f)
    gt, valid = get("gt"), get("valid") > 0.5
    hyp, full, coarse = get("full_hyp"), get("full"), get("coarse")
    ke = shapes.get("full_even", len(hyp))
    m = valid & (gt > 0) & (np.abs(hyp[:ke] - gt[None]).min(0) > 5)
    rr, cc = np.nonzero(m)
    ch, cw = coarse.shape
    # The nearest coarse pixel: columns 4 apart, rows corner-aligned as the grids are.
    cr = np.clip(np.round(rr * (ch - 1) / (H - 1)).astype(int), 0, ch - 1)
    ccol = np.round(cc / 4).astype(int) % cw
    cand = np.stack([coarse[np.clip(cr + dy, 0, ch - 1), (ccol + dx) % cw]
                     for dy in (-1, 0, 1) for dx in (-1, 0, 1)])  # [9, P]
    ims = standardised_images(ds, cfg, cams, f)
    costs = {'mean': [], 'min': []}
    for k in range(9):
        inv = np.maximum(min_inv + cand[k] * step, 1e-6)
        c = pair_costs(*patch_colours(cams, ims, R, rr, cc, inv))
        costs['mean'].append(np.nan_to_num(c['mean_zncc'], nan=9.0))
        costs['min'].append(np.nan_to_num(c['min_zncc'], nan=9.0))
    g = gt[rr, cc]
    err = np.abs(cand - g[None])
    out['ans'].append(np.abs(full - gt)[rr, cc])
    out['oracle'].append(err.min(0))
    out['bilinear_like'].append(err[4])
    for k in ('mean', 'min'):
        pick = np.argmin(np.stack(costs[k]), 0)
        out[k].append(np.take_along_axis(err, pick[None], 0)[0])
r = {k: np.concatenate(v) for k, v in out.items()}
print(f"{d}, frames {a}-{b}: {len(r['ans'])} gross-miss pixels")
for k, name in (('ans', "the network's answer"), ('bilinear_like', 'the nearest coarse answer'),
                ('mean', 'pick by the mean over pairs'), ('min', 'pick by the best pair'),
                ('oracle', 'the best candidate (oracle)')):
    print(f"  {name:30} MAE {r[k].mean():6.2f}  within 5 {100 * (r[k] <= 5).mean():5.1f} %")
