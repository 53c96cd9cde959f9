# The coarse photometric cue in variants (grid, image level, depths per sphere) on validation
# frames: how often its best sphere lies within +-9 index units of the truth on the coarse grid.
# Usage: cue_study.py DATASET FRAME,FRAME,...   (numpy, scipy, omni_np from ../shared/tools)
# Does a denser / finer photometric cue find the truth where the network misses (far, flat,
# repetitive texture)?  ZNCC 5x5 over camera pairs, as the cascade's cue, at grid (h, w) from
# images of pyramid level L; argmax over spheres, scored on the coarse grid against the truth.
import sys, numpy as np, scipy.ndimage as nd, itertools
import os; sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../../../shared/tools')); import omni_np as o
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
cfg, cams, md = o.load(ds)
N = 192
inv = np.linspace(1.0 / (1.0 / o.EPS), 1.0 / md, N)
def pyr(im, L):
    for _ in range(L):
        h, w = im.shape[0] // 2 * 2, im.shape[1] // 2 * 2
        im = 0.25 * (im[0:h:2, 0:w:2] + im[1:h:2, 0:w:2] + im[0:h:2, 1:w:2] + im[1:h:2, 1:w:2])
    return im
def box(x):  # 5x5 mean, columns wrap, rows clamp
    return nd.uniform_filter(x, size=5, mode=('nearest', 'wrap'))
def cue_volume(images, h, w, L, spheres):
    R = o.rays(h, w, 45.0)
    vol = np.zeros((len(spheres), h, w), np.float32)
    ims = [pyr(im, L) for im in images]
    for k, n in enumerate(spheres):
        X = R / inv[n]
        vals, oks = [], []
        for c, im in zip(cams, ims):
            col, row, valid = c.project(X)
            s = 2.0 ** L
            v, ok = o.bilinear(im, (col + 0.5) / s - 0.5, (row + 0.5) / s - 0.5)
            ok = ok & valid
            vals.append(np.where(ok, v, 0).reshape(h, w)); oks.append(ok.reshape(h, w).astype(float))
        tot = np.zeros((h, w)); cnt = np.zeros((h, w))
        for a, b in itertools.combinations(range(len(cams)), 2):
            seen = box(oks[a] * oks[b]) > 0.999
            ma, mb = box(vals[a]), box(vals[b])
            va = box(vals[a] ** 2) - ma ** 2; vb = box(vals[b] ** 2) - mb ** 2
            cov = box(vals[a] * vals[b]) - ma * mb
            z = cov / np.sqrt(np.maximum(va, 0) * np.maximum(vb, 0) + 1e-4)
            tot += np.where(seen, z, 0); cnt += seen
        vol[k] = np.where(cnt > 0, tot / np.maximum(cnt, 1), 0)
    return vol
def pool(vol, f):
    k, h, w = vol.shape
    return vol.reshape(k, h // f, f, w // f, f).mean(axis=(2, 4))
coarse = np.round(np.linspace(0, N - 1, 32)).astype(int)
res = {}
for fr in frames:
    images = [o.read_gray(o.frame_path(ds, i, cfg, fr)) for i in range(len(cams))]
    gt = o.gt_reference(ds, fr, 160, 640, 45.0)
    gi, valid, _, _ = o.reference_gt_index(gt, md)
    g = np.where(valid, gi, -50)
    dx = np.abs(np.diff(g, axis=1, append=g[:, :1])) > 6
    dy = np.zeros_like(dx); dy[:-1] = np.abs(np.diff(g, axis=0)) > 6
    dist = nd.distance_transform_edt(~(dx | dy | np.roll(dx, 1, axis=1) | np.roll(dy, 1, axis=0)))
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
        vol = pool(cue_volume(images, h, w, L, sph), f)
        if m > 1:  # max over the m sub-spheres of each coarse sphere
            vol = vol.reshape(m, len(coarse), *vol.shape[1:]).max(axis=0); sph = coarse
        best = sph[np.argmax(vol, axis=0)]
        for rn, m in regions.items():
            r = res.setdefault((name, rn), [0, 0])
            r[0] += m.sum(); r[1] += (np.abs(best - gc)[m] <= 9).sum()
    print('frame', fr, 'done', flush=True)
for (name, rn), (n, ok) in res.items():
    print(f'{name:45s} {rn:9s} pixels {n:6d}  cue argmax within +-9 of truth: {100 * ok / max(n, 1):5.1f} %')
