# Does an SGM aggregation of the coarse photometric cue find the truth where the raw cue misses?
# Usage: sgm_cue.py DATASET FRAME,FRAME,... [NAME=DIR ...]   (numpy, scipy, tifffile, omni_np)
# The cue as the cascade's (half-resolution grid, half-size images, 3 depths per coarse sphere,
# 2x2 means), then SGM (8 paths, longitude wrapping) on the cost (1 - cue)/2 at the coarse grid
# (40x160) over 32 spheres (each the best of its depths) or all 96 depths, for several penalty
# pairs; HALF=1 adds the aggregation on the half-resolution grid before the 2x2 means. Each
# variant's best sphere is scored on the coarse grid against the truth (within +-9 index units,
# mean |error|) in all pixels, open ones (12+ px from a depth edge) and far open ones (truth
# index < 40); NAME=DIR scores the index maps of an `infer` output (e.g. the network's, SGM's)
# the same way, at the coarse grid's pixels.
import sys, os, numpy as np, time
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o, N, hypotheses, coarse_spheres, cue_volume, pool, sgm, truth  # noqa: E402
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
extra = sys.argv[3:]
half = os.environ.get('HALF') == '1'
cfg, cams, md = o.load(ds)
inv = hypotheses(md)
coarse = coarse_spheres()
sub3 = np.clip(np.concatenate([coarse - 2, coarse, coarse + 2]), 0, N - 1)
res = {}
def score(name, best, regions, gc):
    for rn, m in regions.items():
        r = res.setdefault((name, rn), [0, 0, 0.0])
        r[0] += m.sum(); r[1] += (np.abs(best - gc)[m] <= 9).sum(); r[2] += np.abs(best - gc)[m].sum()
for fr in frames:
    t = time.time()
    images = [o.read_gray(o.frame_path(ds, i, cfg, fr)) for i in range(len(cams))]
    gi, valid, dist = truth(ds, fr, md)
    gc, vc, dc = gi[1::4, 1::4], valid[1::4, 1::4], dist[1::4, 1::4]
    regions = {'all': vc, 'far-flat': vc & (gc < 40) & (dc >= 12), 'open': vc & (dc >= 12)}
    v96 = pool(cue_volume(cams, inv, images, 80, 320, 1, sub3), 2)        # 96 x 40 x 160
    v32 = v96.reshape(3, 32, 40, 160).max(axis=0)
    score('cue 32 (now)', coarse[np.argmax(v32, 0)], regions, gc)
    # 96 depths in index order
    order = np.argsort(sub3, kind='stable'); s96 = sub3[order]; v96o = v96[order]
    score('cue 96', s96[np.argmax(v96o, 0)], regions, gc)
    for p1, p2 in [(0.05, 0.5), (0.1, 1.0), (0.1, 2.0), (0.2, 2.0)]:
        a = sgm((1 - v32) / 2, p1, p2)
        score(f'sgm32 p1 {p1} p2 {p2}', coarse[np.argmin(a, 0)], regions, gc)
    for p1, p2 in [(0.05, 1.0), (0.1, 2.0)]:
        a = sgm((1 - v96o) / 2, p1, p2)
        score(f'sgm96 p1 {p1} p2 {p2}', s96[np.argmin(a, 0)], regions, gc)
    if half:
        vh = cue_volume(cams, inv, images, 80, 320, 1, sub3)[order]
        for p1, p2 in [(0.05, 1.0), (0.1, 2.0)]:
            a = pool(sgm((1 - vh) / 2, p1, p2), 2)
            score(f'sgm96 half grid p1 {p1} p2 {p2}', s96[np.argmin(a, 0)], regions, gc)
    for spec in extra:
        name, d = spec.split('=')
        import tifffile
        idx = tifffile.imread(f'{d}/{fr:05d}_index.tiff').astype(np.float64)
        score(name, idx[1::4, 1::4], regions, gc)
    print('frame', fr, 'done', round(time.time() - t, 1), 's', flush=True)
for (name, rn), (n, ok, ae) in sorted(res.items(), key=lambda kv: (kv[0][1], kv[0][0])):
    print(f'{name:28s} {rn:9s} pixels {n:6d}  within +-9: {100 * ok / max(n, 1):5.1f} %  mean |err| {ae / max(n, 1):6.2f}')
