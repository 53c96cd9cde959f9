#!/usr/bin/env python3
"""Golden outputs for the omnimvs-net parity test.

Builds an OmniMVS network in PyTorch with the layout and state-dict key names of the
public reference implementation (published-weights variant: 18 feature convolutions),
random weights and random batch-norm statistics, runs it in eval mode on deterministic
inputs and writes

    parity.pt          checkpoint {'net_state_dict': ..., 'CH': CH}, like the reference
    parity.json        sizes and the list of raw tensors below
    *.f32              raw little-endian float32 tensors (C order)

The lookup table is an analytic function of (camera, sphere, row, col), recomputed by the
Rust test (`grid_value` there), so it is not stored. Written independently of the
reference code (GPL), from the layer description of the paper's Table 1.

Usage: python3 scripts/net_parity/make_parity.py OUT_DIR
"""
import json
import math
import os
import sys

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

# Sizes: N/2, H/2, W/2 multiples of 16.
CH = 4
NUM_INVDEPTH = 32
OUT_H, OUT_W = 32, 64
NUM_CAMS = 4
IN_H, IN_W = 40, 46
SEED = 1234


class Block(nn.Module):
    """conv (2D, 3D or transposed 3D) -> optional BN -> (+ residual) -> optional ReLU."""

    def __init__(self, conv, bn=None, relu=True):
        super().__init__()
        self.conv = conv
        if bn is not None:
            self.bn = bn
        self.relu = relu

    def forward(self, x, residual=None):
        x = self.conv(x)
        if hasattr(self, "bn"):
            x = self.bn(x)
        if residual is not None:
            x = x + residual
        return F.relu(x) if self.relu else x


def conv2d(cin, cout, k, s, p, d=1, bn=True, relu=True):
    return Block(nn.Conv2d(cin, cout, k, s, padding=p, dilation=d),
                 nn.BatchNorm2d(cout) if bn else None, relu)


def conv3d(cin, cout, s):
    return Block(nn.Conv3d(cin, cout, 3, s, padding=1), nn.BatchNorm3d(cout), True)


def deconv3d(cin, cout, bn_relu=True):
    return Block(nn.ConvTranspose3d(cin, cout, 3, 2, padding=1, output_padding=1),
                 nn.BatchNorm3d(cout) if bn_relu else None, bn_relu)


class Features(nn.Module):
    def __init__(self, ch):
        super().__init__()
        layers = [conv2d(1, ch, 5, 2, 2)]
        for d in [1, 1, 1, 1, 1, 2, 3, 4]:
            layers += [conv2d(ch, ch, 3, 1, d, d), conv2d(ch, ch, 3, 1, d, d)]
        layers.append(conv2d(ch, ch, 3, 1, 1, bn=False, relu=False))
        self.layers = nn.ModuleList(layers)

    def forward(self, x):
        x = self.layers[0](x)
        for i in range(8):
            x = self.layers[2 + 2 * i](self.layers[1 + 2 * i](x), residual=x)
        return self.layers[17](x)


class Sweep(nn.Module):
    def __init__(self, ch):
        super().__init__()
        self.transfer_conv = conv2d(ch, ch, 3, 2, 1, bn=False, relu=False)

    def forward(self, feature, grid):
        # grid: [N/2, H, W, 2]; one grid_sample per sphere, spheres become the batch.
        warped = torch.cat([F.grid_sample(feature, grid[d:d + 1], mode="bilinear",
                                          padding_mode="zeros", align_corners=True)
                            for d in range(grid.shape[0])], 0)
        return warped, self.transfer_conv(warped)  # [N/2, CH, H/2, W/2]


class Cost(nn.Module):
    def __init__(self, ch, cams):
        super().__init__()
        c = 2 * ch
        self.fusion = conv3d(cams * ch, c, 1)
        convs = [conv3d(c, c, 1) for _ in range(3)]
        for cin, cout in [(c, 2 * c), (2 * c, 2 * c), (2 * c, 2 * c), (2 * c, 4 * c)]:
            convs += [conv3d(cin, cout, 2), conv3d(cout, cout, 1), conv3d(cout, cout, 1)]
        self.convs = nn.ModuleList(convs)
        self.deconv1 = deconv3d(4 * c, 2 * c)
        self.deconv2 = deconv3d(2 * c, 2 * c)
        self.deconv3 = deconv3d(2 * c, 2 * c)
        self.deconv4 = deconv3d(2 * c, c)
        self.deconv5 = deconv3d(c, 1, bn_relu=False)

    def forward(self, x):
        cv = self.convs
        c = cv[0](self.fusion(x))
        skips = []
        for level in range(5):
            if level > 0:
                c = cv[3 * level](c)
            skips.append(cv[3 * level + 2](cv[3 * level + 1](c)))
        c = self.deconv1(skips[4], residual=skips[3])
        c = self.deconv2(c, residual=skips[2])
        c = self.deconv3(c, residual=skips[1])
        c = self.deconv4(c, residual=skips[0])
        return self.deconv5(c)


class Net(nn.Module):
    def __init__(self, ch, cams):
        super().__init__()
        self.feature_layers = Features(ch)
        self.spherical_sweep = Sweep(ch)
        self.cost_computes = Cost(ch, cams)


def grid_value(cam, sphere, row, col):
    """Analytic lookup table, mirrored by the Rust test. Some entries are invalid (-1e5
    pixels in the reference, normalised here to a large negative value), some fall
    partly outside the image."""
    a = 2.0 * math.pi * (col + 0.5) / OUT_W + cam * math.pi / 2.0
    r = 0.15 + 0.8 * (row + 0.5) / OUT_H
    x = 1.05 * r * math.cos(a) + 0.01 * sphere * math.sin(a + row)
    y = 1.05 * r * math.sin(a) - 0.01 * sphere * math.cos(a - col)
    if (cam + row + 3 * col + sphere) % 11 == 0:
        x, y = -2e5 / (IN_W - 1) - 1.0, -2e5 / (IN_H - 1) - 1.0
    return x, y


def make_grids():
    grids = np.zeros((NUM_CAMS, NUM_INVDEPTH // 2, OUT_H, OUT_W, 2), np.float64)
    for cam in range(NUM_CAMS):
        for s in range(NUM_INVDEPTH // 2):
            for row in range(OUT_H):
                for col in range(OUT_W):
                    grids[cam, s, row, col] = grid_value(cam, s, row, col)
    return grids.astype(np.float32)


def image_value(cam, row, col):
    """Deterministic smooth pattern with some noise-like structure, mirrored in Rust."""
    return math.sin(0.37 * row + 1.3 * cam) * math.cos(0.23 * col - 0.7 * cam) + \
        0.5 * math.sin(0.05 * row * col + cam)


def randomize(net):
    g = torch.Generator().manual_seed(SEED)
    with torch.no_grad():
        for name, p in net.named_parameters():
            p.copy_((torch.rand(p.shape, generator=g) * 2 - 1) * (1.0 / math.sqrt(max(1, p[0].numel()))))
        for m in net.modules():
            if isinstance(m, (nn.BatchNorm2d, nn.BatchNorm3d)):
                n = m.num_features
                m.weight.copy_(0.5 + 0.5 * torch.rand(n, generator=g))
                m.bias.copy_(0.1 * torch.randn(n, generator=g))
                m.running_mean.copy_(0.1 * torch.randn(n, generator=g))
                m.running_var.copy_(0.5 + torch.rand(n, generator=g))
                m.num_batches_tracked.fill_(7)


def run(net, imgs, grids):
    feats = [net.feature_layers(im) for im in imgs]
    warped0, _ = net.spherical_sweep(feats[0], grids[0])
    spherical = [net.spherical_sweep(f, g)[1] for f, g in zip(feats, grids)]
    vol = torch.cat(spherical, 1).permute(1, 0, 2, 3).unsqueeze(0)  # [1, cams*CH, N/2, H/2, W/2]
    cost = net.cost_computes(vol).squeeze(1)  # [1, N, H, W]
    prob = F.softmax(cost, 1)
    idx = (prob * torch.arange(NUM_INVDEPTH, dtype=torch.float32).view(1, -1, 1, 1)).sum(1)
    entropy = -(prob * torch.log(prob + sys.float_info.epsilon)).sum(1)
    # Only the first spheres of the warped features, to keep the fixture small.
    return dict(feature0=feats[0], warped0=warped0[:4], spherical0=spherical[0], cost=cost,
                index=idx, entropy=entropy)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    torch.manual_seed(SEED)
    net = Net(CH, NUM_CAMS)
    randomize(net)
    net.eval()
    grids = torch.from_numpy(make_grids())
    imgs = [torch.tensor([[[[image_value(c, r, k) for k in range(IN_W)] for r in range(IN_H)]]],
                         dtype=torch.float32) for c in range(NUM_CAMS)]
    with torch.no_grad():
        res = run(net, imgs, grids)
        # Spread the costs so that the softmax is far from uniform.
        scale = 3.0 / float(res["cost"].std(dim=1).mean())
        net.cost_computes.deconv5.conv.weight.mul_(scale)
        net.cost_computes.deconv5.conv.bias.mul_(scale)
        res = run(net, imgs, grids)
    torch.save({"net_state_dict": net.state_dict(), "CH": CH}, os.path.join(out, "parity.pt"))
    tensors = {}
    for name, t in res.items():
        arr = t.detach().numpy().astype("<f4")
        arr.tofile(os.path.join(out, name + ".f32"))
        tensors[name] = list(arr.shape)
    meta = dict(channels=CH, num_invdepth=NUM_INVDEPTH, out_height=OUT_H, out_width=OUT_W,
                num_cameras=NUM_CAMS, input_height=IN_H, input_width=IN_W,
                torch_version=torch.__version__, tensors=tensors)
    with open(os.path.join(out, "parity.json"), "w") as f:
        json.dump(meta, f, indent=1)
    print(json.dumps(meta))
    print("index range", float(res["index"].min()), float(res["index"].max()),
          "mean entropy", float(res["entropy"].mean()), "of at most", math.log(NUM_INVDEPTH))


if __name__ == "__main__":
    main()
