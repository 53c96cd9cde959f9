# The inputs of a learnt pick (`omnimvs_net::pick::PickRefiner::inputs` computes the same in
# Rust) from a network's `omnimvs infer` outputs, with the ground truth the trainer scores against.
#
# Per output pixel (160 x 640, index units of N = 192):
#   - the answer v / 192 and the coarse spread / 30 (`_spread.tiff` beside the answer);
#   - for each radius r of PICK_DEPTH_RADII, with m and M the minimum and maximum of the answers
#     over the (2 r + 1)^2 pixels around (columns wrap in longitude, rows stop at the border):
#     (M - m) / 32, (m - v) / 32, (M - v) / 32;
#   - at each sampled depth (v, then m and M of each radius), every camera's gray value there
#     (each image normalised to zero mean and unit standard deviation) and whether it sees the
#     point;
#   - with PICK_ZNCC = k > 0, per sampled depth: the mean over the camera pairs that count of the
#     ZNCC of their gray values over the k x k pixels of the output grid around (each pixel at its
#     own depth of that map; columns wrap, rows stop at the border; a pair counts where both see
#     the centre and both see at least half the window), and the fraction of the pairs that count.
#
# Options (environment): PICK_DEPTH_RADII, comma-separated radii (default "2"); PICK_ZNCC, the
# ZNCC window's side (default 0, none). The defaults are the bundled picks' layout: 29 channels
# for four cameras. A pick's weights record the layout in their metadata (train_pick.py).
#
# Geometry, ground truth and TIFF reading come from geometry.py beside this file (the dataset
# conventions in numpy, as the Rust crates implement them). Needs numpy, scipy, pillow, pyyaml.
#
# Usage: pick_inputs.py DATASET OUTDIR A B DST.npz
#   DATASET   a dataset folder (`omnimvs synth` output: config.yaml, the cameras' images, the truth)
#   OUTDIR    `omnimvs infer --pick off` of DATASET for frames A..B (%05d.tiff, %05d_spread.tiff)
#   DST.npz   feats (frames, channels, 160, 640) float16, v and gt (frames, 160, 640) float32 in
#             index units (gt below 0 where nothing is scored: sky just below 0, holes -1), valid
import os
import sys

import numpy as np

import geometry
from pick_common import minmax

DEPTH_RADII = tuple(int(r) for r in os.environ.get("PICK_DEPTH_RADII", "2").split(","))
ZNCC = int(os.environ.get("PICK_ZNCC", "0"))


def normalise(im):
    """An image as the pick reads it: gray (the mean of its channels), zero mean, unit standard
    deviation (float64)."""
    im = np.asarray(im).astype(np.float64)
    im = im.mean(-1) if im.ndim == 3 else im
    return (im - im.mean()) / (im.std() + 1e-9)


def normalised_images(ds, f, cfg, cams):
    """Frame f's camera images, each normalised (normalise)."""
    from PIL import Image
    return [normalise(Image.open(geometry.frame_path(ds, i, cfg, f))) for i in range(len(cams))]


def box_sum(a, k):
    """Sum over k x k around each pixel: columns wrapping, rows cut at the border."""
    p = k // 2
    ap = np.concatenate([a[:, a.shape[1] - p:], a, a[:, :p]], 1)
    rows = np.cumsum(np.pad(ap, ((0, 0), (1, 0))), 1)
    ap = rows[:, k:] - rows[:, :-k]
    cols = np.cumsum(np.pad(ap, ((p + 1, p), (0, 0))), 0)
    return cols[k:] - cols[:-k]


def zncc(grays, sees, k):
    """Mean ZNCC over the pairs of cameras that count, and the fraction that count (see the top):
    grays and sees are lists of H x W maps, one per camera."""
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


def channels(cameras, depth_radii=None, zncc_k=None):
    """The number of input channels for a rig of `cameras` (PickLayout::input_channels)."""
    depth_radii = DEPTH_RADII if depth_radii is None else depth_radii
    zncc_k = ZNCC if zncc_k is None else zncc_k
    depths = 1 + 2 * len(depth_radii)
    return 2 + 3 * len(depth_radii) + 2 * cameras * depths + (2 * depths if zncc_k else 0)


def features(ims, cams, v, spread, min_inv, step, phi_deg=45.0, depth_radii=None, zncc_k=None):
    """The inputs (channels, H, W) for the answer v and the spread (index units, H x W), from the
    normalised images `ims` of the cameras `cams` (geometry.Camera): see the top for the layout."""
    depth_radii = DEPTH_RADII if depth_radii is None else depth_radii
    zncc_k = ZNCC if zncc_k is None else zncc_k
    h, w = v.shape
    R = geometry.rays(h, w, phi_deg)
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
            val, ok = geometry.bilinear(im, col, row)
            ok = (vis & ok).astype(np.float64)
            grays.append((val * ok).reshape(h, w)); sees.append(ok.reshape(h, w))
            chans += [grays[-1], sees[-1]]
        sampled.append((grays, sees))
    if zncc_k:
        for grays, sees in sampled:
            chans += list(zncc(grays, sees, zncc_k))
    return np.stack(chans)


def frame_feats(ds, outdir, f, cfg, cams, md):
    """Frame f's inputs (float16), answer v, truth index gt (float32) and validity, at 160 x 640."""
    g = geometry
    pred = g.read_f32_tiff(f"{outdir}/{f:05d}.tiff")
    spread = g.read_f32_tiff(f"{outdir}/{f:05d}_spread.tiff")
    gi, valid, min_inv, step = g.reference_gt_index(g.gt_reference(ds, f, 160, 640, 45.0, cfg), md)
    v = (pred - min_inv) / step
    x = features(normalised_images(ds, f, cfg, cams), cams, v, spread, min_inv, step)
    return x.astype(np.float16), v.astype(np.float32), gi.astype(np.float32), valid


def main():
    if len(sys.argv) != 6:
        raise SystemExit("usage: pick_inputs.py DATASET OUTDIR A B DST.npz (see the top of the file)")
    ds, outdir, a, b, dst = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
    cfg, cams, md = geometry.load(ds)
    F, V, G, M = [], [], [], []
    for f in range(a, b + 1):
        x, v, g, m = frame_feats(ds, outdir, f, cfg, cams, md)
        F.append(x); V.append(v); G.append(g); M.append(m)
    # Written beside DST first, then renamed: an interrupted run leaves no DST behind.
    np.savez(dst + ".tmp.npz", feats=np.stack(F), v=np.stack(V), gt=np.stack(G), valid=np.stack(M))
    os.replace(dst + ".tmp.npz", dst)
    print(dst, len(F), "frames")


if __name__ == "__main__":
    main()
