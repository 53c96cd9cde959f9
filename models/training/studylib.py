"""What the numpy studies under models/training/ share (cascade-23/cue_study.py and
error_split.py, cascade-24/sgm_cue.py, cascade-25/half_study.py, edge_split.py, edge_kinds.py):
omni_np (the independent reading of FORMATS.md in ../shared/tools), the cascade's photometric
cue at a grid's rays, semi-global matching of a cost volume with longitude wrapping, each
pixel's distance to the nearest depth edge of the truth, and for cascade-35's studies a
`cascade_dump` frame's arrays and the cameras' colour agreement at given depths.

A study imports it with
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
    from studylib import o, ...
"""
import itertools
import os
import sys
import warnings

import numpy as np
import scipy.ndimage as nd

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../../shared/tools'))
import omni_np as o  # noqa: E402

N = 192
"""Inverse-depth hypotheses of the paper's tables."""


def hypotheses(min_depth):
    """The N inverse depths (1/m) of a sweep from infinity to `min_depth`."""
    return np.linspace(1.0 / (1.0 / o.EPS), 1.0 / min_depth, N)


def index_scale(min_depth):
    """Inverse depth (1/m) of index 0 and of one index unit of N (as the reference's
    loadGTInvdepthIndex has them): inverse depth = first + index * step."""
    first = 1.0 / (1.0 / o.EPS)
    return first, (1.0 / min_depth - first) / (N - 1.0)


def block_span(index_map, s):
    """Per pixel of the grid `s` times coarser than the 160 x 640 `index_map` (rows
    corner-aligned, columns `s` apart), the span (max - min) of `index_map` over the `s x s`
    output pixels around its centre (rows clamp, longitude wraps)."""
    h, w = 160 // s, 640 // s
    centre_rows = np.round(np.arange(h) * 159 / (h - 1)).astype(int)
    cols = (np.arange(w)[:, None] * s + np.arange(-s // 2, s // 2)[None, :]) % 640
    span = np.zeros((h, w))
    for r in range(h):
        rows = np.clip(np.arange(centre_rows[r] - s // 2, centre_rows[r] + s // 2), 0, 159)
        block = index_map[rows][:, cols]  # [s, w, s]
        span[r] = block.max(axis=(0, 2)) - block.min(axis=(0, 2))
    return span


def coarse_spheres():
    """The cascade's 32 coarse spheres, evenly spaced in index over 0..N-1."""
    return np.round(np.linspace(0, N - 1, 32)).astype(int)


def pyr(im, L):
    """Level L of the image's pyramid of 2x2 means."""
    for _ in range(L):
        h, w = im.shape[0] // 2 * 2, im.shape[1] // 2 * 2
        im = 0.25 * (im[0:h:2, 0:w:2] + im[1:h:2, 0:w:2] + im[0:h:2, 1:w:2] + im[1:h:2, 1:w:2])
    return im


def box(x):
    """5x5 mean; columns wrap, rows clamp."""
    return nd.uniform_filter(x, size=5, mode=('nearest', 'wrap'))


def cue_volume(cams, inv, images, h, w, L, spheres):
    """The cascade's photometric cue: ZNCC over 5x5 windows of the grid (h x w, +-45 degrees),
    averaged over the camera pairs that see the window, from images of pyramid level L, at the
    inverse depths inv[n] of `spheres`: (len(spheres), h, w)."""
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
    """f x f means of every plane."""
    k, h, w = vol.shape
    return vol.reshape(k, h // f, f, w // f, f).mean(axis=(2, 4))


def sgm_step(prev, c, p1, p2):
    """One step along a path: prev, c (..., K)."""
    m = prev.min(axis=-1, keepdims=True)
    up = np.concatenate([prev[..., 1:], np.full(prev.shape[:-1] + (1,), 1e9)], axis=-1)
    dn = np.concatenate([np.full(prev.shape[:-1] + (1,), 1e9), prev[..., :-1]], axis=-1)
    best = np.minimum(np.minimum(prev, np.minimum(up, dn) + p1), m + p2)
    return c + best - m


def sgm(cost, p1, p2):
    """cost (K, H, W) -> summed 8-path costs; longitude wraps (the horizontal paths run two
    laps, the second summed)."""
    C = np.transpose(cost, (1, 2, 0)).astype(np.float64)  # H W K
    H, W, K = C.shape
    S = np.zeros_like(C)
    for dx in (1, -1):
        L = C[:, 0 if dx == 1 else W - 1].copy()
        order = list(range(W)) if dx == 1 else list(range(W - 1, -1, -1))
        for lap in range(2):
            for x in order:
                L = sgm_step(L, C[:, x], p1, p2) if not (lap == 0 and x == order[0]) else C[:, x].copy()
                if lap == 1: S[:, x] += L
    for dy in (1, -1):
        rows = range(H) if dy == 1 else range(H - 1, -1, -1)
        for dx in (-1, 0, 1):
            L = None
            for y in rows:
                if L is None: L = C[y].copy()
                else: L = sgm_step(np.roll(L, dx, axis=0), C[y], p1, p2)
                S[y] += L
    return np.transpose(S, (2, 0, 1))


def edge_distance(gi, valid):
    """Per pixel of the 160x640 grid, the distance (pixels) to the nearest depth discontinuity
    of the truth: neighbours more than 6 index units apart, invalid pixels at -50; longitude
    wraps."""
    g = np.where(valid, gi, -50)
    dx = np.abs(np.diff(g, axis=1, append=g[:, :1])) > 6
    dy = np.zeros_like(dx); dy[:-1] = np.abs(np.diff(g, axis=0)) > 6
    return nd.distance_transform_edt(~(dx | dy | np.roll(dx, 1, axis=1) | np.roll(dy, 1, axis=0)))


def truth(ds, frame, min_depth):
    """The reference's truth of a frame on the 160x640 grid: index (N units), validity, and
    the distance to the nearest depth edge."""
    gi, valid, _, _ = o.reference_gt_index(o.gt_reference(ds, frame, 160, 640, 45.0), min_depth)
    return gi, valid, edge_distance(gi, valid)


def dump_frame(dump_dir, frame):
    """One frame of a `cascade_dump` (`cargo run --release -p omnimvs-train --example
    cascade_dump`): its JSON of shapes and a reader `get(name)` of each raw `f32` array."""
    import json
    shapes = json.load(open(f"{dump_dir}/{frame:05d}.json"))

    def get(name):
        return np.fromfile(f"{dump_dir}/{frame:05d}_{name}.f32", "<f4").reshape(shapes[name])
    return shapes, get


def standardised_images(ds, cfg, cams, frame):
    """The cameras' colour images of a frame (gray repeated), each channel standardised."""
    from PIL import Image
    ims = []
    for i in range(len(cams)):
        im = np.asarray(Image.open(o.frame_path(ds, i, cfg, frame))).astype(np.float64)
        im = np.stack([im] * 3, -1) if im.ndim == 2 else im[..., :3]
        ims.append((im - im.mean((0, 1))) / (im.std((0, 1)) + 1e-9))
    return ims


def patch_colours(cams, ims, rays, rows, cols, inv, radius=1):
    """The colours of the (2 radius + 1)^2 panorama pixels around each pixel (`rows`, `cols` of
    `rays`, [3, H, W]; rows clamp, longitude wraps) at inverse depth `inv` (per pixel), in each
    camera: values [cameras, pixels, 3 (2 radius + 1)^2] and whether a camera sees all of them."""
    h, w = rays.shape[1:]
    n = (2 * radius + 1) ** 2 * 3
    vals = np.zeros((len(cams), len(rows), n))
    vis = np.ones((len(cams), len(rows)), bool)
    t = 0
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            X = rays[:, np.clip(rows + dy, 0, h - 1), (cols + dx) % w] / inv
            for i, cam in enumerate(cams):
                col, row, v = cam.project(X)
                for k in range(3):
                    val, ok = o.bilinear(ims[i][..., k], col, row)
                    vals[i, :, t * 3 + k] = val
                    vis[i] &= ok & v
            t += 1
    return vals, vis


def pair_costs(vals, vis):
    """Colour disagreement of `patch_colours` between the cameras that both see a pixel: mean
    |difference| (sad) and 1 - ZNCC (zncc), as the mean over the camera pairs and the best
    pair: a dict of per-pixel arrays, NaN where no pair sees it."""
    cams = vals.shape[0]
    pairs = list(itertools.combinations(range(cams), 2))
    sad = np.full((len(pairs), vals.shape[1]), np.nan)
    zn = np.full_like(sad, np.nan)
    for p, (i, j) in enumerate(pairs):
        both = vis[i] & vis[j]
        ci = vals[i] - vals[i].mean(1, keepdims=True)
        cj = vals[j] - vals[j].mean(1, keepdims=True)
        z = 1 - (ci * cj).sum(1) / np.sqrt((ci ** 2).sum(1) * (cj ** 2).sum(1) + 1e-9)
        sad[p] = np.where(both, np.abs(vals[i] - vals[j]).mean(1), np.nan)
        zn[p] = np.where(both, z, np.nan)
    with np.errstate(all='ignore'), warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        return dict(mean_sad=np.nanmean(sad, 0), min_sad=np.nanmin(sad, 0),
                    mean_zncc=np.nanmean(zn, 0), min_zncc=np.nanmin(zn, 0))
