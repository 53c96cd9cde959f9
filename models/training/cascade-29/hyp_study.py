"""Does the full-resolution stage get the truth among its hypotheses at depth edges, and does it
pick it? Reads what `cargo run --release -p omnimvs-train --example cascade_dump -- WEIGHTS
DATASET A B OUT [HALF,FULL]` wrote (training ground truth on the output grid; sky, index 0,
left out) and splits the pixels by the distance to the nearest depth edge of that truth
(studylib.edge_distance).

    python3 hyp_study.py DUMP_DIR A B [LABEL]
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import edge_distance  # noqa: E402

d, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
label = sys.argv[4] if len(sys.argv) > 4 else d
rows = {k: [] for k in ("near", "mid", "far")}
for f in range(a, b + 1):
    shapes = json.load(open(f"{d}/{f:05d}.json"))
    get = lambda n: np.fromfile(f"{d}/{f:05d}_{n}.f32", "<f4").reshape(shapes[n])  # noqa: E731
    gt, valid = get("gt"), get("valid") > 0.5
    full, hyp, prob = get("full"), get("full_hyp"), get("full_prob")
    half = get("half")
    # The centre: the middle of the evenly spaced hypotheses (the first `full_even`; dumps
    # before it had only those).
    centre = hyp[shapes.get("full_even", len(hyp)) // 2]
    ok = valid & (gt > 0)
    dist = edge_distance(gt, valid)
    err_h = np.abs(hyp - gt[None])                   # [K, H, W]
    best = err_h.min(0)                              # oracle over the hypotheses
    near_k = err_h.argmin(0)
    p_best = np.take_along_axis(prob, near_k[None], 0)[0]
    arg = np.take_along_axis(hyp, prob.argmax(0)[None], 0)[0]
    half_up = np.kron(half, np.ones((2, 2)))         # nearest parent, for the half stage's error
    extra = prob[shapes.get("full_even", len(hyp)):].sum(0)  # weight on neighbour hypotheses
    for name, m in (("near", dist < 4), ("mid", (dist >= 4) & (dist < 16)), ("far", dist >= 16)):
        m = m & ok
        rows[name].append(np.stack([
            np.abs(full - gt)[m], best[m], np.abs(arg - gt)[m], np.abs(centre - gt)[m],
            p_best[m], (best[m] <= 1.0), np.abs(half_up - gt)[m],
            (hyp.max(0) - hyp.min(0))[m], extra[m]]))
print(f"{label}: frames {a}-{b}; per pixel class: share, MAE of the answer, of the best "
      "hypothesis (oracle), of the most probable one, of the centre, of the half stage (nearest "
      "parent); share with a hypothesis within 1 of the truth; mean probability on the nearest "
      "hypothesis; mean span of the hypotheses; mean weight on the neighbour hypotheses "
      "(`neighbour_hypotheses`, 0 without)")
total = sum(np.concatenate(r, 1).shape[1] for r in rows.values())
for name, r in rows.items():
    r = np.concatenate(r, 1)
    n = r.shape[1]
    print(f"  {name:4} {100 * n / total:5.1f} %  answer {r[0].mean():6.2f}  oracle {r[1].mean():6.2f}"
          f"  argmax {r[2].mean():6.2f}  centre {r[3].mean():6.2f}  half {r[6].mean():6.2f}"
          f"  within1 {100 * r[5].mean():5.1f} %  p(nearest) {r[4].mean():.3f}  span {r[7].mean():5.2f}"
          f"  p(neighbour hypotheses) {r[8].mean():.3f}")
allr = np.concatenate([np.concatenate(r, 1) for r in rows.values()], 1)
print(f"  all  answer {allr[0].mean():.3f}  oracle {allr[1].mean():.3f}  argmax {allr[2].mean():.3f}"
      f"  centre {allr[3].mean():.3f}")

# Where the truth lies around a pixel in the earlier stages' answers: per output pixel, the
# best of the (2r + 1)^2 coarse (or half-grid) answers around its parent (rows clamp, columns
# wrap), near an edge (< 4 px) and over all pixels.
print("the best of the earlier stages' answers around each pixel's parent: MAE, share within 1 "
      "and within 3 of the truth")
for name, scale in (("coarse", 4), ("half", 2)):
    for r in (0, 1, 2):
        found = {"near": [], "all": []}
        for f in range(a, b + 1):
            shapes = json.load(open(f"{d}/{f:05d}.json"))
            get = lambda n: np.fromfile(f"{d}/{f:05d}_{n}.f32", "<f4").reshape(shapes[n])  # noqa: E731
            gt, valid = get("gt"), get("valid") > 0.5
            ok = valid & (gt > 0)
            near = ok & (edge_distance(gt, valid) < 4)
            m = get(name)
            best = np.full(gt.shape, np.inf)
            for dy in range(-r, r + 1):
                rows_ = np.clip(np.arange(m.shape[0]) + dy, 0, m.shape[0] - 1)
                for dx in range(-r, r + 1):
                    s = np.roll(m[rows_], -dx, axis=1)
                    best = np.minimum(best, np.abs(np.kron(s, np.ones((scale, scale))) - gt))
            found["near"].append(best[near])
            found["all"].append(best[ok])
        for cls, v in found.items():
            v = np.concatenate(v)
            print(f"  {name:6} {2 * r + 1}x{2 * r + 1} {cls:4}  MAE {v.mean():6.2f}  within1 "
                  f"{100 * (v <= 1).mean():5.1f} %  within3 {100 * (v <= 3).mean():5.1f} %")
