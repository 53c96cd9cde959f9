# Would an SGM-aggregated cue on the half-resolution grid fix the network's misses in the open?
# On the half grid (80x320): the cue at 96 depths (3 per coarse sphere), SGM (P1 .05/.1, P2 1/2),
# the best plane (no sub-plane refinement); the network's and SGM's maps sampled at the half
# grid's pixels; share with |error| > 3 and MAE by region.
# Usage: half_study.py DATASET FRAME,FRAME,... [NAME=DIR ...]  (numpy, scipy, tifffile, ../studylib.py)
import os, sys, numpy as np, tifffile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o, N, hypotheses, coarse_spheres, cue_volume, sgm, truth  # noqa: E402
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
extra = sys.argv[3:]
cfg, cams, md = o.load(ds)
inv = hypotheses(md)
coarse = coarse_spheres()
sub3 = np.clip(np.concatenate([coarse - 2, coarse, coarse + 2]), 0, N - 1)
order = np.argsort(sub3, kind='stable'); s96 = sub3[order].astype(float)
res = {}
for fr in frames:
    images = [o.read_gray(o.frame_path(ds, i, cfg, fr)) for i in range(len(cams))]
    gi, valid, dist = truth(ds, fr, md)
    gh, vh_, dh = gi[::2, ::2], valid[::2, ::2], dist[::2, ::2]
    regions = {'all': vh_, 'open(16+)': vh_ & (dh >= 16), 'far-open': vh_ & (dh >= 16) & (gh < 40), 'mid(4-16)': vh_ & (dh >= 4) & (dh < 16)}
    vol = cue_volume(cams, inv, images, 80, 320, 1, sub3)[order]
    cands = {}
    for p1, p2 in [(0.05, 1.0), (0.1, 2.0)]:
        a = sgm((1 - vol) / 2, p1, p2)
        k = np.argmin(a, 0)
        cands[f'sgm-half {p1}/{p2}'] = s96[k]
    cands['raw cue'] = s96[np.argmax(vol, 0)]
    for spec in extra:
        name, d = spec.split('=')
        cands[name] = tifffile.imread(f'{d}/{fr:05d}_index.tiff').astype(np.float64)[::2, ::2]
    for name, est in cands.items():
        e = np.abs(est - gh)
        for rn, m in regions.items():
            r = res.setdefault((rn, name), [0, 0, 0.0, 0])
            r[0] += m.sum(); r[1] += (e[m] > 3).sum(); r[2] += e[m].sum(); r[3] += (e[m] > 9).sum()
    print('frame', fr, flush=True)
for (rn, name), (n, b3, ae, b9) in sorted(res.items()):
    print(f'{rn:10s} {name:18s} n {n:6d}  >3 {100*b3/n:5.1f} %  >9 {100*b9/n:5.1f} %  MAE {ae/n:6.2f}')
