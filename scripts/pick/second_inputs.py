# The data of a pick that runs after another (`--pick A,B`: B refines A's answer), such as the
# bundled second pick. For each frame of a pick_inputs.py file (F.npz: the answers v a pick reads,
# its inputs, the truth), the first pick's answer r (PyTorch) and pick_inputs.py's inputs for r,
# with the coarse spread of the network's `omnimvs infer` outputs; written as DST.npz with r as v,
# the same truth and validity: what train_pick.py trains the next pick on. Applied to its own
# output with the second pick's weights, it makes a third pick's data, and so on.
#
# The first pick must have the layout the data is made with (pick_inputs.py's PICK_DEPTH_RADII and
# PICK_ZNCC, train_pick.py's PICK_RADII; by default the bundled picks'). A .safetensors pick
# whose metadata says otherwise is refused; its width is read from its weights.
#
# Usage: second_inputs.py F.npz DATASET OUTDIR A B PICK DST.npz
#   F.npz     the frames A..B of DATASET as the first pick reads them (pick_inputs.py's output,
#             or this script's for a pick further down the chain)
#   DATASET   the dataset folder; OUTDIR its `omnimvs infer --pick off` outputs (for the spread)
#   PICK      the first pick's weights: a .safetensors file (e.g. the bundled
#             models/omnimvs-cascade-pick.safetensors) or a train_pick.py state dict (.pt)
# Needs PyTorch and what pick_inputs.py needs (geometry.py beside it).
import os
import sys

import numpy as np
import torch

import geometry
import pick_inputs as pi
import train_pick as t


def first_pick(path):
    """The first pick's network (eval mode) from its weights; refuses another layout."""
    state, metadata = t.load_state(path)
    if metadata is not None and metadata != t.layout():
        raise SystemExit(f"{path}: layout {metadata}, but this data is made for {t.layout()} "
                         "(set PICK_RADII, PICK_DEPTH_RADII, PICK_ZNCC as that pick was trained)")
    net = t.UNet(state["e0.0.0.weight"].shape[1], t.width_of(state))
    net.load_state_dict(state)
    net.eval()
    return net


def pick_answer(net, feats, v):
    """The pick's answer (H, W) for one frame's inputs feats (C, H, W) and answers v (H, W)."""
    with torch.no_grad():
        x = torch.as_tensor(np.asarray(feats)[None]).float()
        return t.answer(net(x), torch.as_tensor(t.cands(np.asarray(v)[None])))[0].numpy()


def main():
    if len(sys.argv) != 8:
        raise SystemExit("usage: second_inputs.py F.npz DATASET OUTDIR A B PICK DST.npz (see the top of the file)")
    src, ds, outdir, a, b, pick, dst = sys.argv[1:8]
    a, b = int(a), int(b)
    torch.set_num_threads(1)
    d = np.load(src)
    if len(d["v"]) != b - a + 1:
        raise SystemExit(f"{src} holds {len(d['v'])} frames, not {b - a + 1} (frames {a}..{b})")
    net = first_pick(pick)
    g = geometry
    cfg, cams, md = g.load(ds)
    feats, vs = [], []
    for i, f in enumerate(range(a, b + 1)):
        r = pick_answer(net, d["feats"][i], d["v"][i])
        spread = g.read_f32_tiff(f"{outdir}/{f:05d}_spread.tiff")
        gi, valid, min_inv, step = g.reference_gt_index(g.gt_reference(ds, f, 160, 640, 45.0, cfg), md)
        x = pi.features(pi.normalised_images(ds, f, cfg, cams), cams, r, spread, min_inv, step)
        feats.append(x.astype(np.float16)); vs.append(r.astype(np.float32))
    np.savez(dst + ".tmp.npz", feats=np.stack(feats), v=np.stack(vs), gt=d["gt"], valid=d["valid"])
    os.replace(dst + ".tmp.npz", dst)
    print(dst, len(vs), "frames")


if __name__ == "__main__":
    main()
