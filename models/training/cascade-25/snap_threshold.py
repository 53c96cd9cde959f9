# The threshold of `omnimvs infer --snap-edges PCT` swept on the validation frames 481-500 of
# things-s101 and house-s102: edge_post.py's toggle filter (3x3, one pass: the same rule as
# omnimvs_data::edges::snap_edges) applied to the bundled model's `infer` outputs at PCT % of
# N = 192; reference rules, >1 / >3 / >5 / MAE / RMS. 0 % is the network as it is.
# Usage: snap_threshold.py THINGS_OUT HOUSE_OUT   (`omnimvs infer` outputs of frames 481..500)
import os, sys, numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from edge_post import o, scores, toggle  # noqa: E402
for ds, out in [('/work/data/things-s101', sys.argv[1]), ('/work/data/house-s102', sys.argv[2])]:
    _, _, md = o.load(ds)
    rows = {}
    for f in range(481, 501):
        pred = o.read_f32_tiff(f'{out}/{f:05d}.tiff')
        gi, valid, minv, step = o.reference_gt_index(o.gt_reference(ds, f, 160, 640, 45.0), md)
        v = (pred - minv) / step
        for pct in (0, 4, 6, 8, 10, 12, 16, 24):
            q = v if pct == 0 else toggle(v, 3, pct / 100 * 192, 1)
            rows.setdefault(pct, []).append(scores(q, gi, valid))
    for pct, r in rows.items():
        print(os.path.basename(ds), f'{pct:3d} %', ' / '.join(f'{x:.2f}' for x in np.mean(r, 0)))
