# Error of the cascade and of ZNCC+SGM on the same frames split by distance (pixels) to the nearest
# depth discontinuity of the ground truth (neighbours more than 6 index units apart), all pixels
# and far ones (true index < 40); reference rules at 160x640.
# Usage: error_split.py DATASET OUT1,OUT2 FIRST LAST   (/work/venv-np/bin/python3; numpy, scipy)
import sys, glob, os, numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o, edge_distance  # noqa: E402
ds = sys.argv[1]; outs = sys.argv[2].split(','); a, b = int(sys.argv[3]), int(sys.argv[4])
_, _, md = o.load(ds)
def pred_idx(d, f, minv, step):
    c = [p for p in glob.glob(os.path.join(d, f"{f:05d}*.tif*")) if all(k not in p for k in ("entropy","conf","index"))]
    p = o.upsample(o.read_f32_tiff(sorted(c, key=len)[0]), 160, 640)
    return (p.astype(np.float64) - minv) / step
bins = [0, 1, 2, 3, 4, 6, 8, 12, 16, 1000]
acc = {}
for f in range(a, b + 1):
    gt = o.gt_reference(ds, f, 160, 640, 45.0)
    gi, valid, minv, step = o.reference_gt_index(gt, md)
    # discontinuity: neighbour differs by > 6 index (horizontal or vertical)
    dist = edge_distance(gi, valid)
    ps = [pred_idx(d, f, minv, step) for d in outs]
    far = gi < 40
    for lo, hi in zip(bins[:-1], bins[1:]):
        m = valid & (dist >= lo) & (dist < hi)
        for tag, mm in (('all', m), ('far', m & far)):
            r = acc.setdefault((tag, lo), [0] + [0] * len(outs))
            r[0] += mm.sum()
            for i, p in enumerate(ps): r[i + 1] += (np.abs(p - gi)[mm] > 5.76).sum()
tot = sum(v[0] for k, v in acc.items() if k[0] == 'all')
for tag in ('all', 'far'):
    print(tag, 'dist share% ' + ' '.join(d.split('/')[-1] + '>3' for d in outs) + '  (contribution to total >3, points)')
    for lo in bins[:-1]:
        r = acc[(tag, lo)]; n = max(r[0], 1)
        print(f'  {lo:4d}+ {100*r[0]/tot:5.1f} ' + ' '.join(f'{100*r[i+1]/n:6.1f}' for i in range(len(outs))) + '   ' + ' '.join(f'{100*r[i+1]/tot:5.2f}' for i in range(len(outs))))
