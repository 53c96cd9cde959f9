#!/usr/bin/env python3
"""PyTorch-CPU forward timings of the OmniMVS layout, per stage, for comparison with
`cargo run --release -p omnimvs-net --example bench_forward`. Not part of the test suite.

Same stages as the Rust benchmark: features (all cameras), sweep (grid_sample + transference
conv, all cameras), fusion, cost (3D encoder-decoder), softargmin. Random weights, random
inputs, a synthetic lookup table with the same 220-degree coverage as the Rust one.

Usage: /work/venv-torch/bin/python scripts/net_parity/bench_torch.py [tiny|paper] [repeats]
"""
import math
import os
import resource
import sys
import time

import torch
import torch.nn.functional as F

sys.path.insert(0, os.path.dirname(__file__))
from make_parity import Net  # noqa: E402

PRESETS = {
    "tiny": dict(ch=8, n=64, h=32, w=128, ih=192, iw=200),
    "paper": dict(ch=32, n=192, h=160, w=640, ih=768, iw=800),
}
CAMS = 4
HALF_FOV = math.radians(110.0)


def synthetic_grid(cam, n2, h, w, phi_deg=45.0):
    yaw = 2 * math.pi * cam / CAMS
    rows = torch.arange(h, dtype=torch.float32)
    cols = torch.arange(w, dtype=torch.float32)
    phi = (rows - (h - 1) / 2) / ((h - 1) / 2) * math.radians(phi_deg)
    theta = (cols - w / 2) / (w / 2) * math.pi - yaw
    phi, theta = phi[:, None].expand(h, w), theta[None, :].expand(h, w)
    x, y, z = torch.cos(phi) * torch.sin(theta), torch.sin(phi), torch.cos(phi) * torch.cos(theta)
    angle = torch.acos(z.clamp(-1, 1))
    norm = torch.sqrt(x * x + y * y).clamp_min(1.2e-7)
    grids = []
    for s in range(n2):
        r = angle / HALF_FOV + 0.02 * s / n2
        g = torch.stack([r * x / norm, r * y / norm], -1)
        g[angle > HALF_FOV] = -1e5
        grids.append(g)
    return torch.stack(grids)  # [N/2, H, W, 2]


def main():
    preset = sys.argv[1] if len(sys.argv) > 1 else "tiny"
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    p = PRESETS[preset]
    torch.manual_seed(0)
    net = Net(p["ch"], CAMS).eval()
    grids = [synthetic_grid(c, p["n"] // 2, p["h"], p["w"]) for c in range(CAMS)]
    imgs = [torch.randn(1, 1, p["ih"], p["iw"]) for _ in range(CAMS)]
    disps = torch.arange(p["n"], dtype=torch.float32).view(1, -1, 1, 1)
    print(f"torch {torch.__version__}, threads {torch.get_num_threads()}, preset {preset}")
    rows = []
    with torch.no_grad():
        for run in range(repeats + 1):
            t = {}
            t0 = time.perf_counter()
            feats = [net.feature_layers(x) for x in imgs]
            t1 = time.perf_counter()
            sph = [net.spherical_sweep(f, g)[1] for f, g in zip(feats, grids)]
            t2 = time.perf_counter()
            vol = torch.cat(sph, 1).permute(1, 0, 2, 3).unsqueeze(0)
            del sph
            cc = net.cost_computes
            fused = cc.fusion(vol)
            del vol
            t3 = time.perf_counter()
            # Same as Cost.forward, minus the fusion.
            c = cc.convs[0](fused)
            skips = []
            for level in range(5):
                if level > 0:
                    c = cc.convs[3 * level](c)
                skips.append(cc.convs[3 * level + 2](cc.convs[3 * level + 1](c)))
            c = cc.deconv1(skips[4], residual=skips[3])
            c = cc.deconv2(c, residual=skips[2])
            c = cc.deconv3(c, residual=skips[1])
            c = cc.deconv4(c, residual=skips[0])
            cost = cc.deconv5(c).squeeze(1)
            t4 = time.perf_counter()
            prob = F.softmax(cost, 1)
            idx = (prob * disps).sum(1)
            t5 = time.perf_counter()
            t = dict(features=t1 - t0, sweep=t2 - t1, fusion=t3 - t2, cost=t4 - t3,
                     softargmin=t5 - t4, total=t5 - t0)
            print(("warm-up " if run == 0 else "run     ") +
                  " ".join(f"{k} {v:.3f}s" for k, v in t.items()), flush=True)
            if run > 0:
                rows.append(t)
    med = {k: sorted(r[k] for r in rows)[len(rows) // 2] for k in rows[0]}
    print("median  " + " ".join(f"{k} {v:.3f}s" for k, v in med.items()))
    print(f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
