# Where pick-2's error is, on the things validation frames 481-500 of things-s101 (stop 40), and
# whether ZNCC of the cameras' gray values could tell the candidates apart. Prints
# study_errors.txt. Needs pick-2's and ZNCC+SGM's answers on those frames:
#   omnimvs infer --frames 481..500 --out PICK2 /work/data/things-s101       (the stop 39 binary)
#   omnimvs sgm --frames 481..500 --out SGM /work/data/things-s101
# Usage: study_errors.py PICK2 SGM   (the torch venv: it imports ../pick-1's scripts)
import os, sys, numpy as np
here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "../pick-1"))
os.environ.setdefault("PICK_DEPTH_RADII", "2")
import pick_inputs as pi
from train_pick import cands
o = pi.o
from scipy import ndimage

pick2, sgm = sys.argv[1], sys.argv[2]
d = np.load("/work/data2/v-things.npz")
ds = "/work/data/things-s101"
cfg, cams, md = o.load(ds)
_, _, min_inv, step = o.reference_gt_index(o.gt_reference(ds, 481, 160, 640, 45.0), md)
V, G, M = d["v"], d["gt"], d["valid"]
frames = range(481, 501)
P = np.stack([(o.read_f32_tiff(f"{pick2}/{f:05d}.tiff") - min_inv) / step for f in frames])
S = np.stack([(o.read_f32_tiff(f"{sgm}/{f:05d}.tiff") - min_inv) / step for f in frames])
e, es = np.abs(P - G), np.abs(S - G)
print("MAE over all scored pixels of the 20 frames (percent of N = 192):")
for name, x in (("network alone", V), ("with pick-2", P), ("ZNCC+SGM", S)):
    ex = np.abs(x - G)[M]
    print(f"  {name}: {ex.mean() / 1.92:.3f}; {np.mean(ex > 10) * 100:.1f} % of pixels off by more than 10"
          f" index units, {ex[ex > 10].sum() / ex.sum() * 100:.0f} % of the error")


def extremes(v, r):
    k = 2 * r + 1
    vp = np.concatenate([v[..., -r:], v, v[..., :r]], -1)
    return (ndimage.minimum_filter(vp, size=(1, k, k), mode="nearest")[..., r:-r],
            ndimage.maximum_filter(vp, size=(1, k, k), mode="nearest")[..., r:-r])


C = cands(V, (1, 2, 4))
oc = np.abs(C - G[:, None]).min(1)
print("\nThe best of the candidates (an oracle pick), MAE:")
print(f"  pick-2's seven (v, 3x3, 5x5, 9x9 extremes): {oc[M].mean() / 1.92:.3f}")
for r in (7, 12, 20):
    mn, mx = extremes(V, r)
    c2 = np.concatenate([C, mn[:, None], mx[:, None]], 1)
    print(f"  and the {2 * r + 1}x{2 * r + 1} extremes: {np.abs(c2 - G[:, None]).min(1)[M].mean() / 1.92:.3f}")
print(f"  pick-2's seven and ZNCC+SGM's answer: {np.minimum(oc, es)[M].mean() / 1.92:.3f}")
print(f"  pick-2's answer or ZNCC+SGM's: {np.minimum(e, es)[M].mean() / 1.92:.3f}")

print("\npick-2's error by size (index units):")
tot = e[M].sum()
for lo, hi in ((0, 3), (3, 10), (10, 30), (30, 200)):
    m = M & (e >= lo) & (e < hi)
    print(f"  {lo}-{hi}: {m.sum() / M.sum() * 100:.1f} % of pixels, {e[m].sum() / tot * 100:.0f} % of the error;"
          f" a candidate within 3 at {np.mean(oc[m] < 3) * 100:.0f} %, ZNCC+SGM within 3 at {np.mean(es[m] < 3) * 100:.0f} %")
edge = np.stack([(ndimage.maximum_filter(g, 9) - ndimage.minimum_filter(g, 9)) > 10 for g in G])
for name, m in (("within 4 pixels of a depth step of the truth", M & edge), ("elsewhere", M & ~edge)):
    print(f"  {name}: {m.sum() / M.sum() * 100:.0f} % of pixels, {e[m].sum() / tot * 100:.0f} % of the error,"
          f" MAE {e[m].mean() / 1.92:.2f} (oracle of the seven {oc[m].mean() / 1.92:.2f})")
print("\npick-2's MAE by true index (near = high):")
for lo, hi in ((0, 20), (20, 60), (60, 120), (120, 192)):
    m = M & (G >= lo) & (G < hi)
    print(f"  {lo}-{hi}: {m.sum() / M.sum() * 100:.0f} % of pixels, pick-2 {e[m].mean() / 1.92:.2f},"
          f" network {np.abs(V - G)[m].mean() / 1.92:.2f}, ZNCC+SGM {es[m].mean() / 1.92:.2f}")

# ZNCC over 5x5 of the output grid at each candidate's depth (pick_inputs.zncc), frames 481-490.
print("\nZNCC at the candidates (5x5 window of the output grid), frames 481-490, where the network"
      " is off by more than 10 and a candidate within 3 (the 25x25 extremes added):")
mn, mx = extremes(V, 12)
C2 = np.concatenate([C, mn[:, None], mx[:, None]], 1)
R = o.rays(160, 640, 45.0)
wins = tot_px = 0
am = []
for fi, f in enumerate(range(481, 491)):
    ims = pi.normalised_images(ds, f, cfg, cams)
    Z = []
    for k in range(C2.shape[1]):
        X = R / np.maximum(min_inv + C2[fi, k].reshape(-1) * step, 1e-6)
        grays, sees = [], []
        for cam, im in zip(cams, ims):
            col, row, vis = cam.project(X)
            val, ok = o.bilinear(im, col, row)
            ok = (vis & ok).astype(np.float64)
            grays.append((val * ok).reshape(160, 640)); sees.append(ok.reshape(160, 640))
        Z.append(pi.zncc(grays, sees, 5)[0])
    Z = np.stack(Z)
    err = np.abs(C2[fi] - G[fi][None])
    sel = M[fi] & (err.min(0) < 3) & (err[0] > 10)
    zbest = np.take_along_axis(Z, err.argmin(0)[None], 0)[0]
    wins += np.sum(zbest[sel] > Z[0][sel] + 0.05); tot_px += sel.sum()
    am.append(np.abs(np.take_along_axis(C2[fi], Z.argmax(0)[None], 0)[0] - G[fi])[M[fi]])
print(f"  the best candidate's ZNCC above the answer's by 0.05: {wins / tot_px * 100:.0f} % of {tot_px} pixels")
print(f"  the candidate of the highest ZNCC as the answer: MAE {np.concatenate(am).mean() / 1.92:.3f}"
      f" (the network's {np.abs(V[:10] - G[:10])[M[:10]].mean() / 1.92:.3f})")
