# A learnt pick at the final grid's edges, prototyped outside the network: how much of the
# oracle's gain (edge_post.py) can a small CNN get from cheap per-pixel evidence?
# Candidates per pixel: its own answer and the min / max of its 3x3 and 5x5 neighbourhoods of
# the final index map. Inputs: at each candidate's depth, the four cameras' colours (each image
# normalised per channel) and whether they see it; the candidates' offsets from the answer / 32;
# the band (candidates spread more than T index units). Three 3x3 convolutions of 32 channels
# and a 1x1 to 5 logits; the answer is the softmax-weighted candidate (or the argmax one) inside
# the band, the network's outside it; trained by its L1 against the truth inside the band
# (random 64x256 crops, Adam 1e-3). Scored by the reference's rules, MAE in percent of N = 192.
#   numpy (omni_np's venv):  edge_pick_learnt.py feats DATASET OUTDIR A B OUT.npz
#   torch:                   edge_pick_learnt.py train T ITERS TRAIN.npz[,..] VAL.npz[,..]
#                              [CHANNELS [CANDIDATES [gray]]]
# CHANNELS (32) the width of the convolutions; CANDIDATES (0,1,2,3,4) which candidates it sees
# (0 own, 1-2 the 3x3 min / max, 3-4 the 5x5 ones); gray: each camera's mean of its three
# colours instead of the three.
import os, sys, time
import numpy as np


def feats(ds, outdir, a, b, dst):
    from PIL import Image
    from edge_post import minmax, o
    cfg, cams, md = o.load(ds)
    out = {k: [] for k in ('cand', 'feats', 'gt', 'valid')}
    for f in range(a, b + 1):
        ims = []
        for i in range(len(cams)):
            im = np.asarray(Image.open(o.frame_path(ds, i, cfg, f))).astype(np.float64)
            im = np.stack([im] * 3, -1) if im.ndim == 2 else im[..., :3]
            ims.append((im - im.mean((0, 1))) / (im.std((0, 1)) + 1e-9))
        pred = o.read_f32_tiff(f'{outdir}/{f:05d}.tiff')
        gi, valid, min_inv, step = o.reference_gt_index(o.gt_reference(ds, f, 160, 640, 45.0), md)
        v = (pred - min_inv) / step
        cand = np.stack([v, *minmax(v, 3), *minmax(v, 5)])
        h, w = v.shape
        R = o.rays(h, w, 45.0)
        chans = []
        for c in cand:
            X = R / np.maximum(min_inv + c.reshape(-1) * step, 1e-6)
            for cam, im in zip(cams, ims):
                col, row, vis = cam.project(X)
                cols = [o.bilinear(im[..., k], col, row) for k in range(3)]
                ok = (vis & cols[0][1]).astype(np.float64)
                chans += [x * ok for x, _ in cols] + [ok]
        out['cand'].append(cand.astype(np.float32))
        out['feats'].append(np.stack(chans).reshape(-1, h, w).astype(np.float16))
        out['gt'].append(gi.astype(np.float32)); out['valid'].append(valid)
    np.savez(dst, **{k: np.stack(x) for k, x in out.items()})


def select(d, cands, gray):
    """The candidates `cands` of a feats file, each camera's colours as one gray if `gray`."""
    f = d['feats'].reshape(d['feats'].shape[0], 5, 4, 4, *d['feats'].shape[2:])[:, cands]
    if gray:
        f = np.concatenate([f[:, :, :, :3].mean(3, keepdims=True, dtype=np.float32).astype(np.float16),
                            f[:, :, :, 3:]], 3)
    n = f.shape[0]
    return {**d, 'cand': d['cand'][:, cands], 'feats': f.reshape(n, -1, *f.shape[4:])}


def train(T, iters, train_paths, val_paths, ch=32, cands=(0, 1, 2, 3, 4), gray=False):
    import torch, torch.nn as nn
    torch.manual_seed(0); np.random.seed(0); torch.set_num_threads(2)

    def load(paths):
        d = [np.load(p) for p in paths.split(',')]
        return {k: np.concatenate([x[k] for x in d]) for k in ('cand', 'feats', 'gt', 'valid')}

    tr, va = select(load(train_paths), list(cands), gray), select(load(val_paths), list(cands), gray)
    k = len(cands)

    def inputs(cand, fe):
        cand = torch.as_tensor(cand)
        band = ((cand.max(1, keepdim=True).values - cand.min(1, keepdim=True).values) > T).float()
        return torch.cat([torch.as_tensor(fe).float(), (cand[:, 1:] - cand[:, :1]) / 32.0, band], 1), band, cand

    net = nn.Sequential(nn.Conv2d(tr['feats'].shape[1] + k, ch, 3, padding=1), nn.ReLU(),
                        nn.Conv2d(ch, ch, 3, padding=1), nn.ReLU(), nn.Conv2d(ch, ch, 3, padding=1), nn.ReLU(),
                        nn.Conv2d(ch, k, 1))
    opt = torch.optim.Adam(net.parameters(), 1e-3)

    def evaluate(d):
        rows = []
        with torch.no_grad():
            for i in range(len(d['cand'])):
                x, band, c = inputs(d['cand'][i:i + 1], d['feats'][i:i + 1])
                wts = torch.softmax(net(x), 1)
                soft = (wts * c).sum(1); hard = torch.gather(c, 1, wts.argmax(1, keepdim=True))[:, 0]
                b, v = band[:, 0] > 0, c[:, 0]
                g, ok = torch.as_tensor(d['gt'][i:i + 1]), torch.as_tensor(d['valid'][i:i + 1])
                r = []
                for q in (v, torch.where(b, soft, v), torch.where(b, hard, v)):
                    e = (q - g).abs()[ok] / 1.92
                    r += [(e > 3).float().mean().item() * 100, e.mean().item()]
                rows.append(r)
        return ' '.join(f'{x:.3f}' for x in np.mean(rows, 0))

    n, t0 = len(tr['cand']), time.time()
    print('step, seconds, loss, validation >3 / MAE of: the network, soft pick, hard pick')
    for it in range(iters + 1):
        i, y0, x0 = np.random.randint(n), np.random.randint(0, 160 - 64), np.random.randint(0, 640 - 256)
        sl = (slice(i, i + 1), slice(None), slice(y0, y0 + 64), slice(x0, x0 + 256))
        x, band, c = inputs(tr['cand'][sl], tr['feats'][sl])
        g = torch.as_tensor(tr['gt'][i:i + 1, y0:y0 + 64, x0:x0 + 256])
        ok = torch.as_tensor(tr['valid'][i:i + 1, y0:y0 + 64, x0:x0 + 256]) & (band[:, 0] > 0)
        if ok.sum() == 0:
            continue
        loss = ((torch.softmax(net(x), 1) * c).sum(1) - g).abs()[ok].mean()
        opt.zero_grad(); loss.backward(); opt.step()
        if it % 1000 == 0:
            print(it, f'{time.time() - t0:.0f}', f'{loss.item():.2f}', evaluate(va), flush=True)


if __name__ == '__main__':
    if sys.argv[1] == 'feats':
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        feats(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), sys.argv[6])
    else:
        extra = sys.argv[6:]
        train(float(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5],
              ch=int(extra[0]) if extra else 32,
              cands=tuple(int(c) for c in extra[1].split(',')) if len(extra) > 1 else (0, 1, 2, 3, 4),
              gray=len(extra) > 2 and extra[2] == 'gray')
