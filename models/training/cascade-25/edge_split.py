# Error of index maps (infer/sgm outputs) split by distance to the nearest depth discontinuity of the
# ground truth (pixels: <4, 4-16, 16+, and 16+ with truth < 40), on the 160x640 grid; share >3, MAE
# and summed |error| (MAE-contrib) per region. Usage: edge_split.py DATASET FRAME,... NAME=DIR ...
# The mask is omni_np's reference_gt_index 'valid' (what the reference scores).
import sys, numpy as np, scipy.ndimage as nd, tifffile
import os; sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../../../shared/tools')); import omni_np as o
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
cfg, cams, md = o.load(ds)
res = {}
for fr in frames:
    gt = o.gt_reference(ds, fr, 160, 640, 45.0)
    gi, valid, _, _ = o.reference_gt_index(gt, md)
    g = np.where(valid, gi, -50)
    dx = np.abs(np.diff(g, axis=1, append=g[:, :1])) > 6
    dy = np.zeros_like(dx); dy[:-1] = np.abs(np.diff(g, axis=0)) > 6
    dist = nd.distance_transform_edt(~(dx | dy | np.roll(dx, 1, axis=1) | np.roll(dy, 1, axis=0)))
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
