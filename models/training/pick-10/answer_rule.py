# Stop 45: the answer a pick makes of its candidate weights. Trained and run, the answer is the
# softmax-weighted mean of the candidates. If the weights were calibrated probabilities of each
# candidate being the right one, the weighted median would have the lower expected absolute
# error (2 p (1 - p) |M - m| for the mean of two candidates against min(p, 1 - p) |M - m|), and
# the top candidate would never blend two surfaces. This scores the three on a pick's
# validation inputs: MAE and RMS by the reference's rules (errors over 1.92 = N / 100), and the
# share of pixels off by more than 1.92 and 3 x 1.92 index units.
# Usage: answer_rule.py PICK.pt V.npz [V.npz ...]   (the venv with torch; train_pick.py's UNet)
import os, sys
import numpy as np, torch
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../pick-1"))
import train_pick as tp

torch.set_num_threads(2)
weights = sys.argv[1]
for path in sys.argv[2:]:
    d = tp.load(path)
    net = tp.UNet(d["feats"].shape[1], 16)
    net.load_state_dict(torch.load(weights))
    net.eval()
    scores = {"mean": [], "median": [], "top": [], "network": []}
    with torch.no_grad():
        for i in range(len(d["v"])):
            x = torch.as_tensor(tp.inputs_of(d, i)[None]).float()
            c = tp.cands_of(d, i)
            p = torch.softmax(net(x), 1)[0].numpy()
            gt, ok = d["gt"][i], d["valid"][i]
            order = np.argsort(c, 0)
            cs, ps = np.take_along_axis(c, order, 0), np.take_along_axis(p, order, 0)
            at = np.minimum((np.cumsum(ps, 0) < 0.5).sum(0, keepdims=True), len(c) - 1)
            answers = {"mean": (p * c).sum(0), "median": np.take_along_axis(cs, at, 0)[0],
                       "top": np.take_along_axis(c, p.argmax(0)[None], 0)[0], "network": d["v"][i]}
            for k, a in answers.items():
                e = np.abs(a - gt)[ok] / 1.92
                scores[k].append((e.mean(), (e > 1).mean() * 100, (e > 3).mean() * 100, np.sqrt((e ** 2).mean())))
    for k, s in scores.items():
        mae, over1, over3, rms = np.mean(s, 0)
        print(f"{os.path.basename(path)} {k:7s} MAE {mae:.3f}  >1 {over1:.2f}  >3 {over3:.2f}  RMS {rms:.3f}")
