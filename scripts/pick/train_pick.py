# Trains a learnt pick (`omnimvs_net::pick::PickRefiner`), the small network that runs after the
# cascade at the output grid. A U-Net over pick_inputs.py's inputs scores the candidates of each
# pixel (pick_common.candidates: the answer v and the minimum / maximum of the answers around it,
# by default over 3 x 3, 5 x 5 and 9 x 9, wrapping in longitude); the pick's answer is their
# softmax-weighted mean, so it never leaves the range of the answers around a pixel.
#
# Training: the L1 of the answer against the truth, on 4 bands of 64 rows x the whole width a
# step from random frames of TRAIN, Adam with a one-cycle rate (5 % warm-up). Sky pixels are left
# out of the loss unless SKY_WEIGHT is set (they then weigh that much, with target index 0). A
# fresh pick's head starts at zero weights with biases that put about 96 % of the weight on v.
# Every 1,000 steps (and at the last) it prints the validation MAE of each VAL file in percent of
# N = 192 by the reference's rules (sky not scored), before -> after the pick, with the MAE with
# sky scored as index 0 in brackets, and writes OUT.pt (a PyTorch state dict), OUT.safetensors
# (the same weights with these module names and the layout in the metadata, which
# `PickRefiner::from_bytes` reads: `omnimvs infer --pick OUT.safetensors`) and OUT.pt.ckpt (the
# step, optimiser, schedule and random states). Started again with the same arguments, it
# resumes from OUT.pt.ckpt.
#
# Usage: train_pick.py STEPS TRAIN.npz[,..] VAL.npz[,..] [WIDTH] [OUT.pt] [THREADS]
#   STEPS    steps of the one-cycle schedule
#   TRAIN    pick_inputs.py files (or second_inputs.py's, for a pick run after another), in order
#   VAL      the same for the validation frames (whole panoramas)
#   WIDTH    the U-Net's width (default 16: 16 / 32 / 48 / 64 channels, 0.20 M parameters)
#   OUT.pt   where the weights go (default: not written)
#   THREADS  PyTorch's CPU threads (default 2)
# Options (environment):
#   SKY_WEIGHT=w         weight of sky pixels in the loss, target index 0 (default 0; the bundled
#                        picks: 0.25)
#   PICK_LR=x            the one-cycle schedule's peak rate (default 1e-3)
#   PICK_INIT=P          start from a pick's weights (.pt state dict or .safetensors) instead of
#                        a fresh head; fewer inputs or candidates than asked are widened (below)
#   PICK_RADII=1,2,4     the candidates' radii
#   PICK_DEPTH_RADII, PICK_ZNCC
#                        pick_inputs.py's layout options; only recorded in the metadata here, so
#                        set them as the data was made
#   PICK_MODES=k         also the coarse stage's k most probable modes as candidates, and their
#                        channels as inputs (`PickLayout::coarse_modes`): each TRAIN / VAL file
#                        f-NAME.npz / v-NAME.npz needs m-NAME.npz / mv-NAME.npz beside it (arrays
#                        `modes` and `mode_cands`, made by `models/training/pick-7/pack_modes.py`
#                        at revision ec41632)
#   PICK_NEW_BIAS=b      widening: the new candidates' head starts at zero weights and bias b
#                        (default -10)
#   PICK_NEW_INPUT_SCALE=s
#                        widening: the new inputs' first-layer weights start at PyTorch's
#                        default initialisation times s (default 0: zeros)
#   PICK_TEACHER=T       distil a trained pick T (.pt or .safetensors; its width
#                        PICK_TEACHER_WIDTH, default 16; the same inputs and candidates) into
#                        this one: PICK_DISTILL (default 10) times the KL divergence of this
#                        pick's candidate weights from T's, over every pixel of a step's bands,
#                        is added to the L1
# Needs PyTorch, numpy and scipy.
import os
import sys
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

from pick_common import candidates, layout_metadata, read_safetensors, write_safetensors

RADII = tuple(int(r) for r in os.environ.get("PICK_RADII", "1,2,4").split(","))
MODES = int(os.environ.get("PICK_MODES", "0"))
K = 1 + 2 * len(RADII) + MODES  # candidates
NEW_BIAS = float(os.environ.get("PICK_NEW_BIAS", "-10"))
NEW_INPUT_SCALE = float(os.environ.get("PICK_NEW_INPUT_SCALE", "0"))
SKY_WEIGHT = float(os.environ.get("SKY_WEIGHT", "0"))
TEACHER = os.environ.get("PICK_TEACHER")
DISTILL = float(os.environ.get("PICK_DISTILL", "10"))


class WrapConv(nn.Conv2d):
    """3x3 convolution: columns padded circularly (longitude), rows with zeros."""
    def __init__(s, i, o, st=1):
        super().__init__(i, o, 3, st, padding=(1, 0))

    def forward(s, x):
        return super().forward(F.pad(x, (1, 1, 0, 0), mode="circular"))


def cbr(i, o, s=1):
    return nn.Sequential(WrapConv(i, o, s), nn.ReLU(inplace=True))


class UNet(nn.Module):
    def __init__(s, c, w):
        super().__init__()
        s.e0 = nn.Sequential(cbr(c, w), cbr(w, w))
        s.e1 = nn.Sequential(cbr(w, 2 * w, 2), cbr(2 * w, 2 * w))
        s.e2 = nn.Sequential(cbr(2 * w, 3 * w, 2), cbr(3 * w, 3 * w))
        s.e3 = nn.Sequential(cbr(3 * w, 4 * w, 2), cbr(4 * w, 4 * w))
        s.d2 = cbr(4 * w + 3 * w, 3 * w)
        s.d1 = cbr(3 * w + 2 * w, 2 * w)
        s.d0 = cbr(2 * w + w, w)
        s.head = WrapConv(w, K)
        nn.init.zeros_(s.head.weight)
        with torch.no_grad():  # starts with about 96 % of the weight on the answer itself
            s.head.bias.fill_(-5.0); s.head.bias[0] = 0.0

    def forward(s, x):
        up = lambda a, b: F.interpolate(a, size=b.shape[-2:], mode="bilinear", align_corners=False)
        e0 = s.e0(x); e1 = s.e1(e0); e2 = s.e2(e1); e3 = s.e3(e2)
        d2 = s.d2(torch.cat([up(e3, e2), e2], 1))
        d1 = s.d1(torch.cat([up(d2, e1), e1], 1))
        d0 = s.d0(torch.cat([up(d1, e0), e0], 1))
        return s.head(d0)


# The U-Net's convolutions in order, each with the layers whose outputs it reads (None: the
# pick's inputs); a decoder layer reads a concatenation [upsampled deeper part, skip part]. For
# scripts that cut or grow a trained pick's channels.
UNET_LAYERS = [
    ("e0.0.0", None), ("e0.1.0", ["e0.0.0"]),
    ("e1.0.0", ["e0.1.0"]), ("e1.1.0", ["e1.0.0"]),
    ("e2.0.0", ["e1.1.0"]), ("e2.1.0", ["e2.0.0"]),
    ("e3.0.0", ["e2.1.0"]), ("e3.1.0", ["e3.0.0"]),
    ("d2.0", ["e3.1.0", "e2.1.0"]), ("d1.0", ["d2.0", "e1.1.0"]), ("d0.0", ["d1.0", "e0.1.0"]),
    ("head", ["d0.0"]),
]


def cands(v, radii=None):
    """v (B, H, W) -> (B, K, H, W): pick_common.candidates over `radii` (default PICK_RADII)."""
    return candidates(v, RADII if radii is None else radii)


def inputs_of(d, i, rows=slice(None)):
    """Frame i's inputs (rows of them), with the coarse modes' channels when PICK_MODES is set."""
    x = d["feats"][i, :, rows]
    return np.concatenate([x, d["modes"][i, :, rows]], 0) if MODES else x


def cands_of(d, i, rows=slice(None)):
    """Frame i's candidates (C, rows, W): cands() of its answer, then its coarse modes."""
    c = cands(d["v"][i:i + 1])[0, :, rows]
    return np.concatenate([c, d["mode_cands"][i, :, rows].astype(np.float32)], 0) if MODES else c


def widen(state, inputs):
    """A state dict of fewer inputs or candidates widened to `inputs` and K (PICK_NEW_INPUT_SCALE,
    PICK_NEW_BIAS)."""
    w = state["e0.0.0.weight"]
    if w.shape[1] < inputs:
        # The new inputs' weights: PyTorch's default init times NEW_INPUT_SCALE (0: zeros).
        fresh = WrapConv(inputs, w.shape[0]).weight.detach()[:, w.shape[1]:] * NEW_INPUT_SCALE
        state["e0.0.0.weight"] = torch.cat([w, fresh], 1)
    hw, hb = state["head.weight"], state["head.bias"]
    if hw.shape[0] < K:
        n = K - hw.shape[0]
        state["head.weight"] = torch.cat([hw, torch.zeros(n, *hw.shape[1:])], 0)
        state["head.bias"] = torch.cat([hb, torch.full((n,), NEW_BIAS)], 0)
    return state


def answer(logits, c):
    """The pick's answer: the candidates c weighted by the softmax of their logits (dim 1)."""
    return (torch.softmax(logits, 1) * c).sum(1)


def layout():
    """The inputs' and candidates' layout, as the safetensors' metadata."""
    depth_radii = [int(r) for r in os.environ.get("PICK_DEPTH_RADII", "2").split(",")]
    return layout_metadata(RADII, depth_radii, int(os.environ.get("PICK_ZNCC", "0")), MODES)


def load_state(path):
    """A pick's weights as a state dict, and the layout metadata (None for a .pt state dict)."""
    if path.endswith(".safetensors"):
        tensors, metadata = read_safetensors(path)
        return {k: torch.from_numpy(a) for k, a in tensors.items()}, metadata
    return torch.load(path), None


def width_of(state):
    """The U-Net width of a state dict (the first layer's output channels)."""
    return state["e0.0.0.weight"].shape[0]


def save_safetensors(net, path, metadata=None):
    """Writes a network's weights as float32 safetensors with its module names."""
    write_safetensors({k: v.detach().float().contiguous().numpy() for k, v in net.state_dict().items()},
                      path, metadata)


def safetensors_path(out):
    """OUT.pt -> OUT.safetensors (any other name: the name with .safetensors appended)."""
    return (out[:-3] if out.endswith(".pt") else out) + ".safetensors"


def modes_path(p):
    """The coarse modes' file of a pick_inputs.py file (f-NAME.npz: m-NAME.npz; v-NAME: mv-NAME)."""
    head, base = os.path.split(p)
    return os.path.join(head, ("m-" if base.startswith("f-") else "mv-") + base[2:])


def load(paths):
    """The frames of comma-separated pick_inputs.py files, concatenated in order."""
    names = paths.split(",")
    files = [np.load(p) for p in names]
    sizes = [len(x["valid"]) for x in files]
    sources = {k: files for k in ("feats", "v", "gt", "valid")}
    if MODES:
        mfiles = [np.load(modes_path(p)) for p in names]
        for p, m, size in zip(names, mfiles, sizes):
            assert len(m["modes"]) == size and m["mode_cands"].shape[1] >= MODES, modes_path(p)
        sources.update(modes=mfiles, mode_cands=mfiles)
    d = {}
    for k, srcs in sources.items():
        # Filled file by file: the whole array once in memory, and one file's at a time besides.
        out, at = None, 0
        for x, size in zip(srcs, sizes):
            # The modes' candidates as float16 (index units: steps of at most 0.125).
            a = x[k][:, :MODES].astype(np.float16) if k == "mode_cands" else x[k]
            if out is None:
                out = np.empty((sum(sizes),) + a.shape[1:], a.dtype)
            out[at:at + size] = a
            at += size
            del a
        d[k] = out
    # The candidates of frame i are cands(v[i]), computed when a step or an evaluation needs
    # them (for all frames at once they would take 11.5 MB a frame).
    # Sky: pick_inputs.py's truth index is -EPS / step there (holes are -1).
    d["sky"] = (d["gt"] < 0) & (d["gt"] > -0.5)
    return d


def main():
    if len(sys.argv) < 4:
        raise SystemExit("usage: train_pick.py STEPS TRAIN.npz[,..] VAL.npz[,..] [WIDTH] [OUT.pt] [THREADS]"
                         " (see the top of the file)")
    steps, trp, vap = int(sys.argv[1]), sys.argv[2], sys.argv[3]
    W = int(sys.argv[4]) if len(sys.argv) > 4 else 16
    out = sys.argv[5] if len(sys.argv) > 5 else None
    torch.set_num_threads(int(sys.argv[6]) if len(sys.argv) > 6 else 2)
    torch.manual_seed(0); np.random.seed(0)
    tr = load(trp)
    vas = [(p, load(p)) for p in vap.split(",")]
    channels = tr["feats"].shape[1] + (tr["modes"].shape[1] if MODES else 0)
    net = UNet(channels, W)
    if os.environ.get("PICK_INIT"):
        net.load_state_dict(widen(load_state(os.environ["PICK_INIT"])[0], channels))
    LR = float(os.environ.get("PICK_LR", "1e-3"))
    teacher = None
    if TEACHER:
        teacher = UNet(channels, int(os.environ.get("PICK_TEACHER_WIDTH", "16")))
        teacher.load_state_dict(load_state(TEACHER)[0])
        teacher.eval()
        for p in teacher.parameters():
            p.requires_grad_(False)
    print("parameters", sum(p.numel() for p in net.parameters()), "inputs", channels,
          "train frames", len(tr["v"]))
    opt = torch.optim.Adam(net.parameters(), LR)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, LR, total_steps=steps + 1, pct_start=0.05)

    def evaluate():
        res = []
        net.eval()
        with torch.no_grad():
            for p, d in vas:
                before, after, sky_before, sky_after = [], [], [], []
                for i in range(len(d["v"])):
                    x = torch.as_tensor(inputs_of(d, i)[None]).float()
                    v, g, ok = d["v"][i], d["gt"][i], d["valid"][i]
                    r = answer(net(x), torch.as_tensor(cands_of(d, i)[None]))[0].numpy()
                    before.append(np.abs(v - g)[ok].mean() / 1.92); after.append(np.abs(r - g)[ok].mean() / 1.92)
                    # With sky scored as index 0 (the protocol's other table).
                    gs, oks = np.where(d["sky"][i], 0.0, g), ok | d["sky"][i]
                    sky_before.append(np.abs(v - gs)[oks].mean() / 1.92); sky_after.append(np.abs(r - gs)[oks].mean() / 1.92)
                res.append(f"{os.path.basename(p).replace('.npz', '')} {np.mean(before):.3f}->{np.mean(after):.3f}"
                           f" (sky {np.mean(sky_before):.3f}->{np.mean(sky_after):.3f})")
        net.train()
        return "  ".join(res)

    n, t0, B, losses = len(tr["v"]), time.time(), 4, []
    height = tr["v"].shape[1]
    # Resumable: OUT.pt.ckpt holds the step, the optimiser, the schedule and both random states
    # as of the last weights written; a run started again with the same arguments goes on from
    # there.
    ckpt, start = (out + ".ckpt") if out else None, 1
    if ckpt and os.path.exists(ckpt):
        st = torch.load(ckpt, weights_only=False)
        net.load_state_dict(st["net"]); opt.load_state_dict(st["opt"]); sched.load_state_dict(st["sched"])
        np.random.set_state(st["np_rng"]); torch.set_rng_state(st["torch_rng"])
        start, t0 = st["step"] + 1, time.time() - st["elapsed"]
        print("resumed after step", st["step"], flush=True)
    else:
        print(0, "s", 0, evaluate(), flush=True)
    for it in range(start, steps + 1):
        rows = [(np.random.randint(n), np.random.randint(0, height - 64 + 1)) for _ in range(B)]
        pick = lambda k: np.stack([tr[k][i, ..., y0:y0 + 64, :] for i, y0 in rows])
        c = torch.as_tensor(np.stack([cands_of(tr, i, slice(y0, y0 + 64)) for i, y0 in rows]))
        x = torch.as_tensor(np.stack([inputs_of(tr, i, slice(y0, y0 + 64)) for i, y0 in rows])).float()
        g, m = torch.as_tensor(pick("gt")), torch.as_tensor(pick("valid"))
        sky = torch.as_tensor(pick("sky"))
        weight = m.float() + SKY_WEIGHT * sky.float()
        if weight.sum() == 0:
            continue
        target = torch.where(sky, torch.zeros_like(g), g)
        logits = net(x)
        loss = ((answer(logits, c) - target).abs() * weight).sum() / weight.sum()
        if teacher is not None:
            with torch.no_grad():
                taught = torch.log_softmax(teacher(x), 1)
            kl = (taught.exp() * (taught - torch.log_softmax(logits, 1))).sum(1).mean()
            loss = loss + DISTILL * kl
        opt.zero_grad(); loss.backward(); opt.step(); sched.step()
        losses.append(loss.item())
        if it % 1000 == 0 or it == steps:
            print(it, "s", f"{time.time() - t0:.0f}", f"loss {np.mean(losses[-1000:]):.3f}", evaluate(), flush=True)
            if out:
                torch.save(net.state_dict(), out)
                torch.save({"net": net.state_dict(), "opt": opt.state_dict(), "sched": sched.state_dict(),
                            "np_rng": np.random.get_state(), "torch_rng": torch.get_rng_state(),
                            "step": it, "elapsed": time.time() - t0}, ckpt + ".tmp")
                os.replace(ckpt + ".tmp", ckpt)
                save_safetensors(net, safetensors_path(out), layout())


if __name__ == "__main__":
    main()
