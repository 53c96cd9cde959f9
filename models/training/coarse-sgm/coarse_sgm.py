# Stop 41's study: semi-global aggregation of the coarse stage's own distribution
# (omnimvs_net::cascade::score_sgm, `coarse_score_sgm`), in numpy on what
# `cargo run --release -p omnimvs-train --example cascade_dump -- WEIGHTS DATASET A B OUT` wrote
# (coarse_prob [K, h, w], coarse_hyp, the coarse answer, and the trainer's ground truth on the
# output grid, sky as index 0). Costs: -log p in nats, clamped at 8; 8 paths, columns wrapping;
# the new distribution softmax(log p - S / T), S the paths' sum less each pixel's least.
# The coarse answer is scored at the output grid (each coarse pixel repeated over its 4 x 4
# block) against the ground truth, over all valid pixels (sky as index 0) and over non-sky ones.
# Usage: coarse_sgm.py DUMP_DIR A B   (the venv of ../../../../shared/tools/omni_np.py)
import json
import sys

import numpy as np

CMAX = 8.0
SETTINGS = [(p1, p2, t) for p1 in (0.5, 1.0) for p2 in (1.0, 2.0, 4.0) for t in (4.0, 8.0, 16.0, 32.0)
            if p2 >= p1]


def load(d, f):
    meta = json.load(open(f"{d}/{f:05d}.json"))
    r = lambda n: np.fromfile(f"{d}/{f:05d}_{n}.f32", dtype="<f4").reshape(meta[n])
    return {n: r(n) for n in ("coarse_prob", "coarse_hyp", "coarse", "gt", "valid")}


def step(prev, cost, p1, p2):
    m = prev.min(0, keepdims=True)
    up = np.full_like(prev, np.inf); up[1:] = prev[:-1] + p1
    dn = np.full_like(prev, np.inf); dn[:-1] = prev[1:] + p1
    return cost + np.minimum(np.minimum(prev, np.minimum(up, dn)), m + p2) - m


def sgm(cost, p1, p2):
    """Sum over 8 paths of the aggregated costs [K, h, w]; columns wrap (a lap of warm-up)."""
    k, h, w = cost.shape
    total = np.zeros_like(cost)
    for dx in (1, -1):
        cols = list(range(w)) if dx == 1 else list(range(w - 1, -1, -1))
        path, lp = np.zeros_like(cost), cost[:, :, cols[0]].copy()
        for lap in range(2):
            for j in cols:
                if not (lap == 0 and j == cols[0]):
                    lp = step(lp, cost[:, :, j], p1, p2)
                if lap == 1:
                    path[:, :, j] = lp
        total += path
    for dy in (1, -1):
        rows = list(range(h)) if dy == 1 else list(range(h - 1, -1, -1))
        for dx in (0, 1, -1):
            path = np.zeros_like(cost)
            lp = cost[:, rows[0], :].copy(); path[:, rows[0], :] = lp
            for i in rows[1:]:
                lp = step(np.roll(lp, dx, axis=1), cost[:, i, :], p1, p2); path[:, i, :] = lp
            total += path
    return total


def main():
    d, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    rows = {s: [] for s in [None] + SETTINGS}
    for f in range(a, b + 1):
        x = load(d, f)
        p, hyp, gt, ok = x["coarse_prob"], x["coarse_hyp"][:, 0, 0], x["gt"], x["valid"] > 0
        cost = np.minimum(-np.log(np.maximum(p, 1e-12)), CMAX).astype(np.float64)
        H, W = gt.shape
        for s in rows:
            if s is None:
                idx = x["coarse"]
            else:
                agg = sgm(cost, s[0], s[1])
                logits = np.log(np.maximum(p, 1e-12)) - (agg - agg.min(0, keepdims=True)) / s[2]
                q = np.exp(logits - logits.max(0, keepdims=True)); q /= q.sum(0, keepdims=True)
                idx = (q * hyp[:, None, None]).sum(0)
            e = np.abs(np.repeat(np.repeat(idx, H // idx.shape[0], 0), W // idx.shape[1], 1) - gt)
            ns = ok & (gt > 0.5)
            rows[s].append((e[ok].mean() / 1.92, (e[ok] > 20).mean() * 100, e[ns].mean() / 1.92,
                            (e[ns] > 20).mean() * 100))
    print(f"{d} frames {a}-{b}: coarse answer, MAE (% of N) and share off by > 20 index units")
    print("setting (p1, p2, T)      with sky: MAE   >20 %   | sky not scored: MAE   >20 %")
    for s, v in rows.items():
        v = np.mean(v, 0)
        name = "the network as it is" if s is None else str(s)
        print(f"{name:24s}  {v[0]:14.3f}  {v[1]:6.1f}   | {v[2]:20.3f}  {v[3]:6.1f}")


if __name__ == "__main__":
    main()
