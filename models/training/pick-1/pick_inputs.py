# The inputs of the learnt pick (stop 39, `omnimvs_net::pick::PickRefiner::inputs`) from a network's
# infer outputs: the answer v (index units of N = 192), the coarse spread, the 5x5 min / max of the
# answers (wrapping in longitude), and at each of the depths v, min, max the four cameras' gray
# values (each image normalised by its mean and standard deviation) and whether they see the point.
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


def features(ims, cams, v, spread, min_inv, step, phi_deg=45.0):
    """The (5 + 6 x cameras, H, W) inputs for the answer v and the spread (index units, H x W)."""
    mn, mx = minmax(v, 5)
    h, w = v.shape
    R = o.rays(h, w, phi_deg)
    chans = [v / 192.0, spread / 30.0, (mx - mn) / 32.0, (mn - v) / 32.0, (mx - v) / 32.0]
    for c in (v, mn, mx):
        X = R / np.maximum(min_inv + c.reshape(-1) * step, 1e-6)
        for cam, im in zip(cams, ims):
            col, row, vis = cam.project(X)
            val, ok = o.bilinear(im, col, row)
            ok = (vis & ok).astype(np.float64)
            chans += [(val * ok).reshape(h, w), ok.reshape(h, w)]
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
