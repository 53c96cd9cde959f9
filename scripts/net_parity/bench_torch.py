#!/usr/bin/env python3
"""PyTorch timings of the OmniMVS layout (forward per stage, training step, peak memory), for
comparison with `omnimvs bench`. Not part of the test suite.

Same stages as the Rust benchmark: features (all cameras), sweep (grid_sample + transference
conv, all cameras), fusion, cost (3D encoder-decoder), softargmin. Random weights, random
inputs, a synthetic lookup table with the same 220-degree coverage as the Rust one.

The training step is the same as `omnimvs bench`'s: the full differentiable forward pass
(grid_sample sweep), the masked L1 loss on a fixed target, backward and an SGD-momentum update.

Usage: python scripts/net_parity/bench_torch.py [tiny|paper] [repeats]
           [--device cpu|cuda[:N]] [--train-steps S] [--threads T]
"""
import argparse
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


def sync(device):
    if device.type == "cuda":
        torch.cuda.synchronize(device)


def forward_stages(net, imgs, grids, disps, device):
    """One inference pass, stage by stage; returns the timings in seconds."""
    sync(device)
    t0 = time.perf_counter()
    feats = [net.feature_layers(x) for x in imgs]
    sync(device)
    t1 = time.perf_counter()
    sph = [net.spherical_sweep(f, g)[1] for f, g in zip(feats, grids)]
    sync(device)
    t2 = time.perf_counter()
    vol = torch.cat(sph, 1).permute(1, 0, 2, 3).unsqueeze(0)
    del sph
    cc = net.cost_computes
    fused = cc.fusion(vol)
    del vol
    sync(device)
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
    sync(device)
    t4 = time.perf_counter()
    prob = F.softmax(cost, 1)
    idx = (prob * disps).sum(1)
    idx.sum().item()
    t5 = time.perf_counter()
    return dict(features=t1 - t0, sweep=t2 - t1, fusion=t3 - t2, cost=t4 - t3,
                softargmin=t5 - t4, total=t5 - t0)


def train_step(net, opt, imgs, grids, disps, target):
    feats = [net.feature_layers(x) for x in imgs]
    sph = [net.spherical_sweep(f, g)[1] for f, g in zip(feats, grids)]
    vol = torch.cat(sph, 1).permute(1, 0, 2, 3).unsqueeze(0)
    cost = net.cost_computes(vol).squeeze(1)
    idx = (F.softmax(cost, 1) * disps).sum(1)
    loss = (idx - target).abs().mean()
    opt.zero_grad()
    loss.backward()
    opt.step()
    return loss.item()


def median(values):
    return sorted(values)[len(values) // 2]


def peak_memory(device):
    if device.type == "cuda":
        return f"peak GPU memory {torch.cuda.max_memory_allocated(device) / 2**20:.0f} MiB"
    return f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("preset", nargs="?", default="tiny", choices=sorted(PRESETS))
    parser.add_argument("repeats", nargs="?", type=int, default=3)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--train-steps", type=int, default=0)
    parser.add_argument("--threads", type=int, default=0)
    args = parser.parse_args()
    if args.threads > 0:
        torch.set_num_threads(args.threads)
    device = torch.device(args.device)
    p = PRESETS[args.preset]
    torch.manual_seed(0)
    net = Net(p["ch"], CAMS).to(device).eval()
    grids = [synthetic_grid(c, p["n"] // 2, p["h"], p["w"]).to(device) for c in range(CAMS)]
    imgs = [torch.randn(1, 1, p["ih"], p["iw"], device=device) for _ in range(CAMS)]
    disps = torch.arange(p["n"], dtype=torch.float32, device=device).view(1, -1, 1, 1)
    print(f"torch {torch.__version__}, device {device}, threads {torch.get_num_threads()}, "
          f"preset {args.preset}")
    rows = []
    with torch.no_grad():
        for run in range(args.repeats + 1):
            t = forward_stages(net, imgs, grids, disps, device)
            print(("warm-up " if run == 0 else "run     ") +
                  " ".join(f"{k} {v:.4f}s" for k, v in t.items()), flush=True)
            if run > 0:
                rows.append(t)
    if rows:
        med = {k: median([r[k] for r in rows]) for k in rows[0]}
        print("median  " + " ".join(f"{k} {v:.4f}s" for k, v in med.items()))
    print(peak_memory(device) + " after the forward passes")
    if args.train_steps > 0:
        net.train()
        opt = torch.optim.SGD(net.parameters(), lr=0.003, momentum=0.9)
        target = (torch.arange(p["h"] * p["w"], dtype=torch.float32, device=device) % 97
                  / 96 * (p["n"] - 1)).view(1, p["h"], p["w"])
        times = []
        for step in range(args.train_steps + 1):
            sync(device)
            t0 = time.perf_counter()
            loss = train_step(net, opt, imgs, grids, disps, target)
            sync(device)
            dt = time.perf_counter() - t0
            print(f"train step {step}{' (warm-up)' if step == 0 else ''}: {dt:.4f}s "
                  f"(loss {loss:.3f})", flush=True)
            if step > 0:
                times.append(dt)
        m = median(times)
        print(f"train step median {m:.4f}s ({1 / m:.2f} steps/s)")
        print(peak_memory(device) + " after the training steps")


if __name__ == "__main__":
    main()
