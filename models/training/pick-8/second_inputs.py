# pick-8 (stop 42): the data of a second pick, run after the bundled one. For each frame of a
# pick_inputs.py file (F.npz: the network's answers v, the inputs, the truth), the bundled pick's
# answer r (pick-6, torch, the weights PICK) and pick_inputs.py's inputs for r with the same coarse
# spread (read from the network's infer outputs OUTDIR), written as DST.npz with r as v: what
# train_pick.py trains the second pick on.
# Usage: second_inputs.py F.npz DATASET OUTDIR A B PICK.pt DST.npz   (the torch venv)
import os, sys
import numpy as np, torch
here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "../pick-1"))
import pick_inputs as pi  # noqa: E402 (it puts shared/tools on the path)
import omni_np as o  # noqa: E402
import train_pick as t  # noqa: E402

src, ds, outdir, a, b, pick, dst = sys.argv[1:8]
a, b = int(a), int(b)
torch.set_num_threads(1)
d = np.load(src)
net = t.UNet(d["feats"].shape[1], 16)
net.load_state_dict(torch.load(pick))
net.eval()
cfg, cams, md = o.load(ds)
feats, vs = [], []
for i, f in enumerate(range(a, b + 1)):
    with torch.no_grad():
        r = t.answer(net(torch.as_tensor(d["feats"][i:i + 1]).float()),
                     torch.as_tensor(t.cands(d["v"][i:i + 1])))[0].numpy()
    spread = o.read_f32_tiff(f"{outdir}/{f:05d}_spread.tiff")
    gi, valid, min_inv, step = o.reference_gt_index(o.gt_reference(ds, f, 160, 640, 45.0), md)
    x = pi.features(pi.normalised_images(ds, f, cfg, cams), cams, r, spread, min_inv, step)
    feats.append(x.astype(np.float16)); vs.append(r.astype(np.float32))
np.savez(dst + ".tmp.npz", feats=np.stack(feats), v=np.stack(vs), gt=d["gt"], valid=d["valid"])
os.replace(dst + ".tmp.npz", dst)
print(dst, len(vs), "frames")
