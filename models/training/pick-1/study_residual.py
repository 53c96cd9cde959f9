# A full-resolution refinement prototype (stop 39): a small U-Net over pick_inputs.py's inputs that
# answers v + 8 * delta, trained by L1 against the truth (sky left out, as the reference scores) on
# random 64 x 256 crops of frames the network never trained on. Validation: whole panoramas, MAE in
# percent of N = 192 (the reference's rules) before and after.
# (stop 39, a first try before train_pick.py: it learnt nothing in 3,000 steps, study_residual.log)
# Usage: study_residual.py STEPS TRAIN.npz[,..] VAL.npz[,..] [WIDTH] [OUT.pt] [THREADS]
import sys, time, numpy as np, torch, torch.nn as nn, torch.nn.functional as F

steps, trp, vap = int(sys.argv[1]), sys.argv[2], sys.argv[3]
W = int(sys.argv[4]) if len(sys.argv) > 4 else 16
out = sys.argv[5] if len(sys.argv) > 5 else None
torch.set_num_threads(int(sys.argv[6]) if len(sys.argv) > 6 else 2)
torch.manual_seed(0); np.random.seed(0)


def load(paths):
    d = [np.load(p) for p in paths.split(",")]
    return {k: np.concatenate([x[k] for x in d]) for k in ("feats", "v", "gt", "valid")}


tr = load(trp)
vas = [(p, load(p)) for p in vap.split(",")]
C = tr["feats"].shape[1]


def cbr(i, o, s=1):
    return nn.Sequential(nn.Conv2d(i, o, 3, s, 1), nn.ReLU(inplace=True))


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
        s.head = nn.Conv2d(w, 1, 3, 1, 1)
        nn.init.zeros_(s.head.weight); nn.init.zeros_(s.head.bias)

    def forward(s, x):
        up = lambda a, b: F.interpolate(a, size=b.shape[-2:], mode="bilinear", align_corners=False)
        e0 = s.e0(x); e1 = s.e1(e0); e2 = s.e2(e1); e3 = s.e3(e2)
        d2 = s.d2(torch.cat([up(e3, e2), e2], 1))
        d1 = s.d1(torch.cat([up(d2, e1), e1], 1))
        d0 = s.d0(torch.cat([up(d1, e0), e0], 1))
        return 8.0 * s.head(d0)[:, 0]


net = UNet(C, W)
print("parameters", sum(p.numel() for p in net.parameters()), "inputs", C, "train frames", len(tr["v"]))
opt = torch.optim.Adam(net.parameters(), 1e-3)
sched = torch.optim.lr_scheduler.OneCycleLR(opt, 1e-3, total_steps=steps + 1, pct_start=0.05)


def evaluate():
    res = []
    net.eval()
    with torch.no_grad():
        for p, d in vas:
            before, after = [], []
            for i in range(len(d["v"])):
                x = torch.as_tensor(d["feats"][i:i + 1]).float()
                v = d["v"][i]; g = d["gt"][i]; ok = d["valid"][i]
                r = v + net(x)[0].numpy()
                before.append(np.abs(v - g)[ok].mean() / 1.92); after.append(np.abs(r - g)[ok].mean() / 1.92)
            res.append(f"{p.split('/')[-1].replace('.npz','')} {np.mean(before):.3f}->{np.mean(after):.3f}")
    net.train()
    return "  ".join(res)


n, t0, B, losses = len(tr["v"]), time.time(), 8, []
print(0, "s", 0, evaluate(), flush=True)
for it in range(1, steps + 1):
    xs, vs, gs, ms = [], [], [], []
    for _ in range(B):
        i, y0, x0 = np.random.randint(n), np.random.randint(0, 160 - 64 + 1), np.random.randint(0, 640 - 256 + 1)
        xs.append(tr["feats"][i, :, y0:y0 + 64, x0:x0 + 256]); vs.append(tr["v"][i, y0:y0 + 64, x0:x0 + 256])
        gs.append(tr["gt"][i, y0:y0 + 64, x0:x0 + 256]); ms.append(tr["valid"][i, y0:y0 + 64, x0:x0 + 256])
    x = torch.as_tensor(np.stack(xs)).float(); v = torch.as_tensor(np.stack(vs))
    g = torch.as_tensor(np.stack(gs)); m = torch.as_tensor(np.stack(ms))
    if m.sum() == 0:
        continue
    loss = ((v + net(x)) - g).abs()[m].mean()
    opt.zero_grad(); loss.backward(); opt.step(); sched.step()
    losses.append(loss.item())
    if it % 500 == 0 or it == steps:
        print(it, "s", f"{time.time() - t0:.0f}", f"loss {np.mean(losses[-500:]):.3f}", evaluate(), flush=True)
        if out:
            torch.save(net.state_dict(), out)
