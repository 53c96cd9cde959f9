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
import sys, os, numpy as np, scipy.ndimage as nd, itertools, time
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../../../shared/tools')); import omni_np as o
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
extra = sys.argv[3:]
half = os.environ.get('HALF') == '1'
cfg, cams, md = o.load(ds)
N = 192
inv = np.linspace(1.0 / (1.0 / o.EPS), 1.0 / md, N)
def pyr(im, L):
    for _ in range(L):
        h, w = im.shape[0] // 2 * 2, im.shape[1] // 2 * 2
        im = 0.25 * (im[0:h:2, 0:w:2] + im[1:h:2, 0:w:2] + im[0:h:2, 1:w:2] + im[1:h:2, 1:w:2])
    return im
def box(x):
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
def step(prev, c, p1, p2):
    # prev, c: (..., K)
    m = prev.min(axis=-1, keepdims=True)
    up = np.concatenate([prev[..., 1:], np.full(prev.shape[:-1] + (1,), 1e9)], axis=-1)
    dn = np.concatenate([np.full(prev.shape[:-1] + (1,), 1e9), prev[..., :-1]], axis=-1)
    best = np.minimum(np.minimum(prev, np.minimum(up, dn) + p1), m + p2)
    return c + best - m
def sgm(cost, p1, p2):
    # cost (K, H, W) -> summed 8-path costs, longitude wraps
    C = np.transpose(cost, (1, 2, 0)).astype(np.float64)  # H W K
    H, W, K = C.shape
    S = np.zeros_like(C)
    for dx in (1, -1):  # horizontal, two laps
        L = C[:, 0 if dx == 1 else W - 1].copy()
        order = list(range(W)) if dx == 1 else list(range(W - 1, -1, -1))
        for lap in range(2):
            for x in order:
                L = step(L, C[:, x], p1, p2) if not (lap == 0 and x == order[0]) else C[:, x].copy()
                if lap == 1: S[:, x] += L
    for dy in (1, -1):
        rows = range(H) if dy == 1 else range(H - 1, -1, -1)
        for dx in (-1, 0, 1):
            L = None
            for y in rows:
                if L is None: L = C[y].copy()
                else: L = step(np.roll(L, dx, axis=0), C[y], p1, p2)
                S[y] += L
    return np.transpose(S, (2, 0, 1))
coarse = np.round(np.linspace(0, N - 1, 32)).astype(int)
sub3 = np.clip(np.concatenate([coarse - 2, coarse, coarse + 2]), 0, N - 1)
res = {}
def score(name, best, regions, gc):
    for rn, m in regions.items():
        r = res.setdefault((name, rn), [0, 0, 0.0])
        r[0] += m.sum(); r[1] += (np.abs(best - gc)[m] <= 9).sum(); r[2] += np.abs(best - gc)[m].sum()
for fr in frames:
    t = time.time()
    images = [o.read_gray(o.frame_path(ds, i, cfg, fr)) for i in range(len(cams))]
    gt = o.gt_reference(ds, fr, 160, 640, 45.0)
    gi, valid, _, _ = o.reference_gt_index(gt, md)
    g = np.where(valid, gi, -50)
    dx = np.abs(np.diff(g, axis=1, append=g[:, :1])) > 6
    dy = np.zeros_like(dx); dy[:-1] = np.abs(np.diff(g, axis=0)) > 6
    dist = nd.distance_transform_edt(~(dx | dy | np.roll(dx, 1, axis=1) | np.roll(dy, 1, axis=0)))
    gc, vc, dc = gi[1::4, 1::4], valid[1::4, 1::4], dist[1::4, 1::4]
    regions = {'all': vc, 'far-flat': vc & (gc < 40) & (dc >= 12), 'open': vc & (dc >= 12)}
    v96 = pool(cue_volume(images, 80, 320, 1, sub3), 2)        # 96 x 40 x 160
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
        vh = cue_volume(images, 80, 320, 1, sub3)[order]
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
