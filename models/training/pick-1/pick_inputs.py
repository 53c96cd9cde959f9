# The inputs of the learnt pick (stop 39, `omnimvs_net::pick::PickRefiner::inputs`) from a network's
# infer outputs: the answer v (index units of N = 192), the coarse spread, the 5x5 min / max of the
# answers (wrapping in longitude), and at each of the depths v, min, max the four cameras' gray
# values (each image normalised by its mean and standard deviation) and whether they see the point.
# pick-3 (stop 40) widened the layout, read from the environment (defaults: pick-1/2's):
#   PICK_DEPTH_RADII="2,12": the radii whose min / max depths are sampled (besides v), each adding
#     (M - m) / 32, (m - v) / 32, (M - v) / 32 to the answer's channels and gray / sees per camera
#     at m and M;
#   PICK_ZNCC=5: per sampled depth, the mean over the camera pairs that both see the point of the
#     ZNCC of their gray values over the 5 x 5 pixels of the output grid around (each at its own
#     depth of that map; wrapping in longitude, rows cut at the border; a pair counts where it
#     sees the centre and at least half the window), and the fraction of the pairs that count.
# Layout: v/192, spread/30, the answer's channels per radius; gray, sees per camera per depth
# (v, then m, M of each radius); then (zncc, pairs) per depth.
# Usage: pick_inputs.py DATASET OUTDIR A B DST.npz   (the venv of ../../../shared/tools/omni_np.py)
import os, sys, numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../../shared/tools"))
sys.path.insert(0, "/work/shared/tools")
import omni_np as o
from PIL import Image
from scipy import ndimage


def minmax(v, k):
    pad = k // 2
    vp = np.concatenate([v[:, -pad:], v, v[:, :pad]], 1)
    mn = ndimage.minimum_filter(vp, size=k, mode="nearest")[:, pad:-pad]
    mx = ndimage.maximum_filter(vp, size=k, mode="nearest")[:, pad:-pad]
    return mn, mx


def normalised_images(ds, f, cfg, cams):
    ims = []
    for i in range(len(cams)):
        im = np.asarray(Image.open(o.frame_path(ds, i, cfg, f))).astype(np.float64)
        im = im.mean(-1) if im.ndim == 3 else im
        ims.append((im - im.mean()) / (im.std() + 1e-9))
    return ims


DEPTH_RADII = tuple(int(r) for r in os.environ.get("PICK_DEPTH_RADII", "2").split(","))
ZNCC = int(os.environ.get("PICK_ZNCC", "0"))


def box_sum(a, k):
    """Sum over k x k around each pixel: columns wrapping, rows cut at the border."""
    p = k // 2
    ap = np.concatenate([a[:, -p:], a, a[:, :p]], 1)
    rows = np.cumsum(np.pad(ap, ((0, 0), (1, 0))), 1)
    ap = rows[:, k:] - rows[:, :-k]
    cols = np.cumsum(np.pad(ap, ((p + 1, p), (0, 0))), 0)
    return cols[k:] - cols[:-k]


def zncc(grays, sees, k):
    """Mean ZNCC over the pairs of cameras that count, and the fraction that count (see top)."""
    num, cnt, pairs = 0.0, 0.0, 0
    for i in range(len(grays)):
        for j in range(i + 1, len(grays)):
            a, b, m = grays[i], grays[j], sees[i] * sees[j]
            n = box_sum(m, k)
            sa, sb = box_sum(m * a, k), box_sum(m * b, k)
            saa, sbb, sab = box_sum(m * a * a, k), box_sum(m * b * b, k), box_sum(m * a * b, k)
            nn = np.maximum(n, 1.0)
            cov, va, vb = sab - sa * sb / nn, saa - sa * sa / nn, sbb - sb * sb / nn
            z = cov / np.sqrt(np.maximum(va, 0) * np.maximum(vb, 0) + (0.01 * n) ** 2 + 1e-12)
            ok = ((m > 0) & (2 * n >= k * k)).astype(np.float64)
            num, cnt, pairs = num + z * ok, cnt + ok, pairs + 1
    return np.where(cnt > 0, num / np.maximum(cnt, 1), 0.0), cnt / max(pairs, 1)


def features(ims, cams, v, spread, min_inv, step, phi_deg=45.0, depth_radii=None, zncc_k=None):
    """The inputs (channels, H, W) for the answer v and the spread (index units, H x W): 5 + 6 x
    cameras for pick-1/2's layout (see top)."""
    depth_radii = DEPTH_RADII if depth_radii is None else depth_radii
    zncc_k = ZNCC if zncc_k is None else zncc_k
    h, w = v.shape
    R = o.rays(h, w, phi_deg)
    chans, depths = [v / 192.0, spread / 30.0], [v]
    for r in depth_radii:
        mn, mx = minmax(v, 2 * r + 1)
        chans += [(mx - mn) / 32.0, (mn - v) / 32.0, (mx - v) / 32.0]
        depths += [mn, mx]
    sampled = []
    for c in depths:
        X = R / np.maximum(min_inv + c.reshape(-1) * step, 1e-6)
        grays, sees = [], []
        for cam, im in zip(cams, ims):
            col, row, vis = cam.project(X)
            val, ok = o.bilinear(im, col, row)
            ok = (vis & ok).astype(np.float64)
            grays.append((val * ok).reshape(h, w)); sees.append(ok.reshape(h, w))
            chans += [grays[-1], sees[-1]]
        sampled.append((grays, sees))
    if zncc_k:
        for grays, sees in sampled:
            chans += list(zncc(grays, sees, zncc_k))
    return np.stack(chans)


def frame_feats(ds, outdir, f, cfg, cams, md):
    pred = o.read_f32_tiff(f"{outdir}/{f:05d}.tiff")
    spread = o.read_f32_tiff(f"{outdir}/{f:05d}_spread.tiff")
    gi, valid, min_inv, step = o.reference_gt_index(o.gt_reference(ds, f, 160, 640, 45.0), md)
    v = (pred - min_inv) / step
    x = features(normalised_images(ds, f, cfg, cams), cams, v, spread, min_inv, step)
    return x.astype(np.float16), v.astype(np.float32), gi.astype(np.float32), valid


if __name__ == "__main__":
    ds, outdir, a, b, dst = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
    cfg, cams, md = o.load(ds)
    F, V, G, M = [], [], [], []
    for f in range(a, b + 1):
        x, v, g, m = frame_feats(ds, outdir, f, cfg, cams, md)
        F.append(x); V.append(v); G.append(g); M.append(m)
    np.savez(dst, feats=np.stack(F), v=np.stack(V), gt=np.stack(G), valid=np.stack(M))
    print(dst, len(F), "frames")
