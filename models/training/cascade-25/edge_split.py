# Error of index maps (infer/sgm outputs) split by distance to the nearest depth discontinuity of the
# ground truth (pixels: <4, 4-16, 16+, and 16+ with truth < 40), on the 160x640 grid; share >3, MAE
# and summed |error| (MAE-contrib) per region. Usage: edge_split.py DATASET FRAME,... NAME=DIR ...
# The mask is omni_np's reference_gt_index 'valid' (what the reference scores).
import os, sys, numpy as np, tifffile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o, truth  # noqa: E402
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
cfg, cams, md = o.load(ds)
res = {}
for fr in frames:
    gi, valid, dist = truth(ds, fr, md)
    regions = {'all': valid, 'near(<4)': valid & (dist < 4), 'mid(4-16)': valid & (dist >= 4) & (dist < 16), 'open(16+)': valid & (dist >= 16), 'far-open': valid & (dist >= 16) & (gi < 40)}
    for spec in sys.argv[3:]:
        name, d = spec.split('=')
        idx = tifffile.imread(f'{d}/{fr:05d}_index.tiff').astype(np.float64)
        e = np.abs(idx - gi)
        for rn, m in regions.items():
            r = res.setdefault((rn, name), [0, 0, 0.0])
            r[0] += m.sum(); r[1] += (e[m] > 3).sum(); r[2] += e[m].sum()
for (rn, name), (n, bad, ae) in sorted(res.items()):
    print(f'{rn:10s} {name:8s} share {n:7d}  >3 {100*bad/n:5.1f} %  MAE {ae/n:6.2f}  MAE-contrib {ae:9.0f}')
