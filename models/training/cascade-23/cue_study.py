# The coarse photometric cue in variants (grid, image level, depths per sphere) on validation
# frames: how often its best sphere lies within +-9 index units of the truth on the coarse grid.
# Usage: cue_study.py DATASET FRAME,FRAME,...   (numpy, scipy, omni_np from ../shared/tools)
# Does a denser / finer photometric cue find the truth where the network misses (far, flat,
# repetitive texture)?  ZNCC 5x5 over camera pairs, as the cascade's cue, at grid (h, w) from
# images of pyramid level L; argmax over spheres, scored on the coarse grid against the truth.
import os, sys, numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o, N, hypotheses, coarse_spheres, cue_volume, pool, truth  # noqa: E402
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
cfg, cams, md = o.load(ds)
inv = hypotheses(md)
coarse = coarse_spheres()
res = {}
for fr in frames:
    images = [o.read_gray(o.frame_path(ds, i, cfg, fr)) for i in range(len(cams))]
    gi, valid, dist = truth(ds, fr, md)
    # the truth on the 40x160 grid: the 4x4 block's centre pixel
    gc, vc, dc = gi[1::4, 1::4], valid[1::4, 1::4], dist[1::4, 1::4]
    regions = {'all': vc, 'far-flat': vc & (gc < 40) & (dc >= 12)}
    sub3 = np.clip(np.concatenate([coarse - 2, coarse, coarse + 2]), 0, N - 1)
    variants = {
        'q-grid, 32 spheres (now)': (40, 160, 2, coarse, 1, 1),
        'half-grid pooled, 32 spheres (cascade-22)': (80, 320, 1, coarse, 2, 1),
        'half-grid pooled, max of 3 per sphere (+-2)': (80, 320, 1, sub3, 2, 3),
        'half-grid pooled, 192 spheres': (80, 320, 1, np.arange(N), 2, 1),
        'full-grid pooled, 32 spheres': (160, 640, 0, coarse, 4, 1),
    }
    for name, (h, w, L, sph, f, m) in variants.items():
        vol = pool(cue_volume(cams, inv, images, h, w, L, sph), f)
        if m > 1:  # max over the m sub-spheres of each coarse sphere
            vol = vol.reshape(m, len(coarse), *vol.shape[1:]).max(axis=0); sph = coarse
        best = sph[np.argmax(vol, axis=0)]
        for rn, m in regions.items():
            r = res.setdefault((name, rn), [0, 0])
            r[0] += m.sum(); r[1] += (np.abs(best - gc)[m] <= 9).sum()
    print('frame', fr, 'done', flush=True)
for (name, rn), (n, ok) in res.items():
    print(f'{name:45s} {rn:9s} pixels {n:6d}  cue argmax within +-9 of truth: {100 * ok / max(n, 1):5.1f} %')
