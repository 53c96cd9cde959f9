#!/usr/bin/env python3
# Hard picks from a stage with neighbour hypotheses: wherever the two hold more than T of the
# weight, the one it weights more instead of the soft answer. Usage: hard_pick.py DUMP_DIR A B
import os
import sys
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import dump_frame  # noqa: E402
d, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
taus = [0.2, 0.3, 0.4, 0.5, 0.6, 0.7]
errs = {t: [] for t in ['soft', 'argmax'] + taus}
for f in range(a, b + 1):
    shapes, get = dump_frame(d, f)
    gt, valid = get("gt"), get("valid") > 0.5
    ok = valid & (gt > 0)
    hyp, prob, full = get("full_hyp"), get("full_prob"), get("full")
    ke = shapes["full_even"]
    pe = prob[ke:].sum(0)
    pick = np.where(prob[ke] > prob[ke + 1], hyp[ke], hyp[ke + 1])
    errs['soft'].append(np.abs(full - gt)[ok])
    arg = np.take_along_axis(hyp, prob.argmax(0)[None], 0)[0]
    errs['argmax'].append(np.abs(arg - gt)[ok])
    for t in taus:
        ans = np.where(pe > t, pick, full)
        errs[t].append(np.abs(ans - gt)[ok])
for k, v in errs.items():
    print(f"{k}: MAE {np.concatenate(v).mean():.3f}")
