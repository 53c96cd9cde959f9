# Stop 45: how well what the cameras see at a pixel tells the right side of a depth edge.
#
# On a pick's validation inputs (pick_inputs.py's layout: the answer v, the 5 x 5 minimum m and
# maximum M of the answers, and at each of v, m and M every camera's normalised gray value and
# whether it sees the point), two questions, scored on the pixels the reference scores:
#
# 1. Where the answer misses by more than T index units and exactly one of m, M is within 2 of
#    the truth (the other more than T off): how often does the right one have the better
#    photometric agreement? Agreements: `var`, the variance of the gray values of the cameras
#    that see the point; `best`, the smallest absolute difference over the camera pairs that see
#    it (an occluded camera cannot spoil it); `rob`, the variance without the camera farthest
#    from the mean (when three or more see it); each per pixel (box 1) and averaged over 3 x 3
#    pixels (box 3). A coin scores 0.5; "always m" is the share of those pixels where the far
#    side is the right one.
# 2. A control: where the answer is right (within 1) and m or M lies more than 10 away (the
#    other surface of an edge), how often does the answer agree better than that extreme?
#
# Also printed: the mean number of cameras that see a scored pixel at its right answer.
# Usage: side_evidence.py V.npz [V.npz ...]   (numpy, scipy: the venv of omni_np.py)
import sys
import numpy as np
from scipy import ndimage


def agreements(x, base, n_cams=4):
    """Per-pixel agreements of the cameras' gray values sampled at one depth (channels base ..)."""
    g = x[:, base:base + 2 * n_cams:2]
    s = x[:, base + 1:base + 2 * n_cams:2]
    n = s.sum(1)
    mean = (g * s).sum(1) / np.maximum(n, 1)
    var = ((g - mean[:, None]) ** 2 * s).sum(1) / np.maximum(n, 1)
    best = np.full(n.shape, 1e9, np.float32)
    for i in range(n_cams):
        for j in range(i + 1, n_cams):
            both = (s[:, i] > 0) & (s[:, j] > 0)
            best = np.where(both, np.minimum(best, np.abs(g[:, i] - g[:, j])), best)
    far = np.argmax(np.abs(g - mean[:, None]) * s, 1)
    s2 = s.copy()
    np.put_along_axis(s2, far[:, None], 0, 1)
    s2 = np.where((n >= 3)[:, None], s2, s)
    n2 = s2.sum(1)
    mean2 = (g * s2).sum(1) / np.maximum(n2, 1)
    rob = ((g - mean2[:, None]) ** 2 * s2).sum(1) / np.maximum(n2, 1)
    none = n < 2
    return {"var": np.where(none, 1e9, var), "best": best, "rob": np.where(none, 1e9, rob)}, n


def boxed(a, box):
    if box == 1:
        return a
    return ndimage.uniform_filter(np.minimum(a, 10.0), size=(1, box, box))


def study(path):
    d = np.load(path)
    x = d["feats"].astype(np.float32)
    v, gt, ok = d["v"], d["gt"], d["valid"]
    m, big = v + x[:, 3] * 32, v + x[:, 4] * 32
    at_v, seen = agreements(x, 5)
    at_m, _ = agreements(x, 13)
    at_big, _ = agreements(x, 21)
    ev, em, eb = np.abs(v - gt), np.abs(m - gt), np.abs(big - gt)
    name = path.split("/")[-1]
    print(f"== {name}: {ok.sum()} scored pixels; cameras seeing a pixel at its right answer: "
          f"mean {seen[ok & (ev <= 1)].mean():.2f}")
    for t in (5, 10):
        right_m = ok & (ev > t) & (em <= 2) & (eb > t)
        right_big = ok & (ev > t) & (eb <= 2) & (em > t)
        both = right_m.sum() + right_big.sum()
        print(f"answer off by more than {t}: m right at {right_m.sum()} px, M right at "
              f"{right_big.sum()} px; always m (the far side) right at {right_m.sum() / max(both, 1):.3f}")
        for k in ("var", "best", "rob"):
            for box in (1, 3):
                a, b = boxed(at_m[k], box), boxed(at_big[k], box)
                hit_m, hit_big = (a < b)[right_m], (b < a)[right_big]
                print(f"  {k:4s} box {box}: right {(hit_m.sum() + hit_big.sum()) / max(both, 1):.3f} "
                      f"(where m is right {hit_m.mean():.3f}, where M is right {hit_big.mean():.3f})")
    print("control: the answer right (within 1), the extreme more than 10 away; the answer agrees better:")
    for label, at_x, off in (("m", at_m, v - m), ("M", at_big, big - v)):
        sel = ok & (ev <= 1) & (np.abs(off) > 10)
        for k in ("var", "best"):
            print(f"  against {label}, {k:4s}: {(at_v[k] < at_x[k])[sel].mean():.3f} of {sel.sum()} px")


if __name__ == "__main__":
    for p in sys.argv[1:]:
        study(p)
