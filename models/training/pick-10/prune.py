# pick-10 (stop 44): a half-width start for the second pick, cut from pick-8b's weights. Every
# feature map of the U-Net (train_pick.py's UNet, width W) keeps the half of its channels whose
# filters (weights and bias) have the largest L2 norm; the layers that read it keep the same input
# channels (the decoder's concatenations keep the kept channels of both parts). The head is kept
# whole. The result is a width W/2 state dict for train_pick.py's PICK_INIT, fine-tuned after.
# Usage: prune.py IN.pt OUT.pt   (the torch venv)
import os, sys
import torch

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../pick-1"))
from train_pick import UNET_LAYERS as layers  # noqa: E402

src = torch.load(sys.argv[1])
w = src["e0.0.0.weight"].shape[0]
half = w // 2


def keep(name, n):
    """The n output channels of layer `name` with the largest filter norms, in order."""
    wt, b = src[name + ".weight"], src[name + ".bias"]
    norm = wt.flatten(1).norm(dim=1) ** 2 + b ** 2
    return torch.sort(torch.topk(norm, n).indices).values


# (layer, input-channel source(s)) in order (train_pick.py's UNET_LAYERS); a source is a previous
# layer's kept outputs, or None for all of the inputs.
kept, out = {}, {}
for name, sources in layers:
    wt, b = src[name + ".weight"], src[name + ".bias"]
    outs = torch.arange(wt.shape[0]) if name == "head" else keep(name, wt.shape[0] // 2)
    kept[name] = outs
    if sources is None:
        ins = torch.arange(wt.shape[1])
    else:
        ins, at = [], 0
        for s in sources:
            ins.append(kept[s] + at)
            at += src[s + ".weight"].shape[0]
        ins = torch.cat(ins)
        assert at == wt.shape[1], (name, at, wt.shape)
    out[name + ".weight"] = wt[outs][:, ins].clone()
    out[name + ".bias"] = b[outs].clone()
assert set(out) == set(src), set(src) ^ set(out)
torch.save(out, sys.argv[2])
print(f"width {w} -> {half}:", sum(v.numel() for v in out.values()), "parameters")
