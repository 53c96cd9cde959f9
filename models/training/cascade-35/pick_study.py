"""Can the four images tell which of a pixel's two neighbour hypotheses is right?

Reads a `cascade_dump` of a network with neighbour hypotheses on the full stage (`cargo run
--release -p omnimvs-train --example cascade_dump -- WEIGHTS DATASET A B OUT`). Population: the
pixels where one of the two extremes (the lowest / highest centre around the pixel) is within
TOL index units of the truth and no evenly spaced hypothesis within 5, the extremes more than 10
apart: the pixels a right pick would fix. Evidence at each extreme's depth: the colours of the
(2 PR + 1)^2 panorama pixels around, projected into each camera (omni_np's camera model; images
standardised per channel), compared between the cameras that see all of them. Pair cost: mean
|difference| (sad) or 1 - ZNCC (zncc); the mean over the pairs or the best pair. Prints how
often each rule, and the network (the extreme it weights more), picks the right extreme, and the
MAE of its pick.

    python3 pick_study.py DUMP_DIR DATASET A B [PR [TOL]]
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import (dump_frame, edge_distance, index_scale, o, pair_costs,  # noqa: E402
                      patch_colours, standardised_images)

d, ds, a, b = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
PR = int(sys.argv[5]) if len(sys.argv) > 5 else 1
TOL = float(sys.argv[6]) if len(sys.argv) > 6 else 3.0
cfg, cams, md = o.load(ds)
H, W = 160, 640
R = o.rays(H, W, 45.0).reshape(3, H, W)
min_inv, step = index_scale(md)
RULES = ('mean_sad', 'min_sad', 'mean_zncc', 'min_zncc')
res = {k: [] for k in ('right_lo', 'net', 'near', 'elo', 'ehi', 'ans') + RULES}
for f in range(a, b + 1):
    shapes, get = dump_frame(d, f)
    gt, valid = get("gt"), get("valid") > 0.5
    hyp, prob = get("full_hyp"), get("full_prob")
    ke = shapes["full_even"]
    lo, hi = hyp[ke], hyp[ke + 1]
    even_best = np.abs(hyp[:ke] - gt[None]).min(0)
    elo, ehi = np.abs(lo - gt), np.abs(hi - gt)
    m = valid & (gt > 0) & (np.minimum(elo, ehi) <= TOL) & (even_best > 5) & (hi - lo > 10)
    rr, cc = np.nonzero(m)
    ims = standardised_images(ds, cfg, cams, f)
    cost = {}
    for name, hv in (('lo', lo), ('hi', hi)):
        inv = np.maximum(min_inv + hv[rr, cc] * step, 1e-6)
        cost[name] = pair_costs(*patch_colours(cams, ims, R, rr, cc, inv, PR))
    res['right_lo'].append((elo < ehi)[rr, cc])
    res['elo'].append(elo[rr, cc])
    res['ehi'].append(ehi[rr, cc])
    res['ans'].append(np.abs(get('full') - gt)[rr, cc])
    res['net'].append((prob[ke] > prob[ke + 1])[rr, cc])
    res['near'].append((edge_distance(gt, valid) < 4)[rr, cc])
    for k in RULES:
        cl, ch = cost['lo'][k], cost['hi'][k]
        res[k].append(np.where(np.isnan(cl), False, np.where(np.isnan(ch), True, cl < ch)))
r = {k: np.concatenate(v) for k, v in res.items()}
print(f"{d}, frames {a}-{b}, {2 * PR + 1}x{2 * PR + 1} patches, tolerance {TOL}: {len(r['ans'])} "
      f"pixels ({100 * r['near'].mean():.1f} % within 4 px of an edge); the right extreme is the "
      f"far one for {100 * r['right_lo'].mean():.1f} %; MAE of the network's answer "
      f"{r['ans'].mean():.2f}, of the better extreme {np.minimum(r['elo'], r['ehi']).mean():.2f}, "
      f"of the far one always {r['elo'].mean():.2f}")
for k in ('net',) + RULES:
    ok = r[k] == r['right_lo']
    mae = np.where(r[k], r['elo'], r['ehi']).mean()
    print(f"  {k:10} right {100 * ok.mean():5.1f} % (where the far one is right "
          f"{100 * ok[r['right_lo']].mean():5.1f} %, the near one {100 * ok[~r['right_lo']].mean():5.1f} %)"
          f"  MAE of its pick {mae:6.2f}")
