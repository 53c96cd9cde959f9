# Stop 44: where the error lies with respect to depth edges. For each output (160 x 640, scored by
# the reference's rules as ../../../../shared/tools/omni_np.py's eval-at does: sky not scored), every
# scored pixel's distance in pixels to the nearest depth edge of the truth (a jump of more than
# JUMP index units to a 4-neighbour, longitude wrapping; sky counts as index 0 there), and its
# side: within 2 pixels of such an edge (5 x 5 extremes more than JUMP apart), the near side (the
# truth above the middle of the extremes) or the far side. Prints, per band, the share of the
# pixels, the share of the error (MAE in percent of N = 192), the MAE there and the signed mean.
# Usage: edge_error.py DATASET OUTPUT_DIR A B   (the venv of omni_np.py: numpy, scipy)
import os, sys
import numpy as np
import scipy.ndimage as nd

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../../shared/tools"))
import omni_np as o  # noqa: E402

JUMP = 20


def edge_distance(g, jump=JUMP):
    """Each pixel's distance (pixels) to the nearest depth edge of the index map `g` (sky as 0):
    a pixel on either side of a jump of more than `jump` to a 4-neighbour, longitude wrapping.
    ../pick-7/miss_categories.py's `edges` mode uses it too."""
    dx = np.abs(g - np.roll(g, 1, 1)) > jump
    dy = np.zeros_like(dx)
    dy[1:] = np.abs(g[1:] - g[:-1]) > jump
    edge = dx | np.roll(dx, -1, 1) | dy | np.roll(dy, -1, 0)
    return nd.distance_transform_edt(~edge)


def main():
    ds, out, a, b = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    _, _, min_depth = o.load(ds)
    rows = []
    for f in range(a, b + 1):
        pred = o.upsample(o.read_f32_tiff(os.path.join(out, f"{f:05d}.tiff")), 160, 640)
        gt = o.gt_reference(ds, f, 160, 640, 45.0)
        gi, valid, min_inv, step = o.reference_gt_index(gt, min_depth)
        g = np.where(gt < 1e-3, 0.0, gi)
        dist = edge_distance(g)
        gp = np.pad(g, ((2, 2), (0, 0)), mode="edge")
        gp = np.concatenate([gp[:, -2:], gp, gp[:, :2]], 1)
        hi = nd.maximum_filter(gp, 5)[2:-2, 2:-2]
        lo = nd.minimum_filter(gp, 5)[2:-2, 2:-2]
        near_edge = hi - lo > JUMP
        side = np.where(near_edge, np.where(g > (hi + lo) / 2, 1, 2), 0)  # 1 near, 2 far
        err = ((pred - min_inv) / step - gi) / 192 * 100
        valid &= np.isfinite(err)
        rows.append(np.stack([err[valid], dist[valid], side[valid]], 1))
    err, dist, side = np.concatenate(rows).T
    ae, total = np.abs(err), np.abs(err).sum()
    print(f"{out}: frames {a}-{b}, {len(err)} pixels, MAE {ae.mean():.3f} (pooled)")
    print("distance to a depth edge | pixels | share of the error | MAE there | signed")
    for lo_, hi_ in [(0, 1.5), (1.5, 3), (3, 5), (5, 8), (8, 12), (12, 20), (20, 1e9)]:
        s = (dist >= lo_) & (dist < hi_)
        label = f"{lo_:g}-{hi_:g} px" if hi_ < 1e9 else f">= {lo_:g} px"
        print(f"{label:>12} | {s.mean():6.3f} | {ae[s].sum() / total:6.3f} | {ae[s].mean():6.2f} | {err[s].mean():+6.2f}")
    for name, k in [("near side, <= 2 px", 1), ("far side, <= 2 px", 2), ("not at an edge", 0)]:
        s = side == k
        print(f"{name:>20} | {s.mean():6.3f} | {ae[s].sum() / total:6.3f} | {ae[s].mean():6.2f} | {err[s].mean():+6.2f}")


if __name__ == "__main__":
    main()
