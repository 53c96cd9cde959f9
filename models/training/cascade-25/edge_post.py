# Can the final 160x640 map's edge blends be turned into picks after the network, without it?
# Usage: edge_post.py DATASET OUTDIR A B   (an `infer` output of frames A..B; numpy, scipy, omni_np)
# Every figure is scored by the reference's rules (omni_np's reference_gt_index and its MAE, in
# percent of N = 192). Per pixel, the candidates are its own answer v and the min m / max M of
# its k x k neighbourhood (longitude wraps); the "band" is where M - m > T index units.
#   toggle k T i:  in the band, v takes whichever of m, M is nearer (i passes): a shock filter
#   far-bias a:    in the band, v takes m if v - m < a (M - m), else M (a 0.5 is the toggle)
#   photo r/pair:  in the band (3x3, T 16), v takes whichever of {v, m, M} the four cameras agree
#                  on best: the colour variance across cameras (or the smallest difference of a
#                  camera pair) at that candidate's depth, box-summed over (2r+1)^2 pixels
#   oracle k:      per pixel whichever of {v, m, M} is nearest the truth (the bound of any pick)
import os, sys, numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o  # noqa: E402


def window(x, k):
    """The k*k shifted copies of x (rows clamped, longitude wrapped), stacked."""
    r = k // 2
    pad = np.pad(x, ((r, r), (0, 0)), mode='edge')
    pad = np.concatenate([pad[:, -r:], pad, pad[:, :r]], axis=1)
    h, w = x.shape
    return np.stack([pad[dy:dy + h, dx:dx + w] for dy in range(k) for dx in range(k)])


def minmax(x, k):
    s = window(x, k)
    return s.min(0), s.max(0)


def toggle(v, k, t, iters):
    for _ in range(iters):
        m, mx = minmax(v, k)
        v = np.where(mx - m > t, np.where(v - m < mx - v, m, mx), v)
    return v


def camera_agreement(cams, ims, idx, min_inv, step, pair):
    """Per pixel: colour variance across the cameras that see the point at index idx, or the
    smallest |difference| of a camera pair that both see it (pair=True); 1e6 where < 2 see it."""
    h, w = idx.shape
    X = o.rays(h, w, 45.0) / np.maximum(min_inv + idx.reshape(-1) * step, 1e-6)
    vals, oks = [], []
    for c, im in zip(cams, ims):
        col, row, vis = c.project(X)
        v, ok = o.bilinear(im, col, row)
        vals.append(v); oks.append(ok & vis)
    V, O = np.stack(vals), np.stack(oks)
    if pair:
        best = np.full(V.shape[1], 1e6)
        for a in range(len(V)):
            for b in range(a + 1, len(V)):
                best = np.where(O[a] & O[b], np.minimum(best, np.abs(V[a] - V[b])), best)
        return best.reshape(h, w)
    n = O.sum(0)
    mean = (V * O).sum(0) / np.maximum(n, 1)
    var = ((V - mean) ** 2 * O).sum(0) / np.maximum(n, 1)
    return np.where(n >= 2, var, 1e6).reshape(h, w)


def scores(q, gi, valid):
    e = np.abs(q - gi)[valid] / 192 * 100
    return [(e > 1).mean() * 100, (e > 3).mean() * 100, (e > 5).mean() * 100, e.mean(), np.sqrt((e ** 2).mean())]


def main():
    ds, outdir, a, b = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    cfg, cams, md = o.load(ds)
    rows, side = {}, []
    for f in range(a, b + 1):
        pred = o.read_f32_tiff(f'{outdir}/{f:05d}.tiff')
        gi, valid, min_inv, step = o.reference_gt_index(o.gt_reference(ds, f, 160, 640, 45.0), md)
        v = (pred - min_inv) / step
        res = {'network': v}
        for k, t, i in [(3, 8, 1), (3, 16, 1), (3, 16, 2), (3, 32, 1), (5, 16, 1), (5, 32, 1)]:
            res[f'toggle k{k} T{t} x{i}'] = toggle(v, k, t, i)
        m, mx = minmax(v, 3)
        band = mx - m > 16
        for al in (0.3, 0.4, 0.6, 0.7):
            res[f'far-bias a{al}'] = np.where(band, np.where(v - m < al * (mx - m), m, mx), v)
        ims = []
        for i in range(len(cams)):
            im = o.read_gray(o.frame_path(ds, i, cfg, f))
            ims.append((im - im.mean()) / (im.std() + 1e-9))
        cand = np.stack([v, m, mx])
        for pair in (False, True):
            agree = np.stack([camera_agreement(cams, ims, c, min_inv, step, pair) for c in cand])
            for r in (0, 1):
                s = np.stack([window(x, 2 * r + 1).mean(0) for x in agree]) if r else agree
                pick = np.take_along_axis(cand, s.argmin(0)[None], 0)[0]
                res[f'photo {"pair" if pair else "variance"} r{r}'] = np.where(band, pick, v)
        for k in (3, 5):
            mk, mxk = minmax(v, k)
            best = np.where(np.abs(mk - gi) < np.abs(mxk - gi), mk, mxk)
            res[f'oracle {k}x{k}'] = np.where(np.abs(v - gi) < np.abs(best - gi), v, best)
        for name, q in res.items():
            rows.setdefault(name, []).append(scores(q, gi, valid))
        miss = band & valid & (np.abs(v - gi) > 5 * 1.92)
        side.append((np.abs(gi - m) < np.abs(gi - mx))[miss].mean())
        print(f'frame {f} done', file=sys.stderr, flush=True)
    print(f'{os.path.basename(ds)} frames {a}-{b}: >1 / >3 / >5 / MAE / RMS (reference rules)')
    for name, r in rows.items():
        print(f'{name:24s} ' + ' / '.join(f'{x:.2f}' for x in np.mean(r, 0)))
    print(f'misses (>5) in the 3x3 band whose truth is the far side (m): {100 * np.mean(side):.1f} %')


if __name__ == '__main__':
    main()
