# pick-11 (stop 45): a wider start for the pick, grown from a trained one. Every feature map of the
# U-Net (train_pick.py's UNet, width W -> W2) keeps the trained channels first; the new channels'
# filters start at PyTorch's default initialisation, and every weight that reads a new channel
# starts at zero, so the grown network answers exactly as the trained one. The decoder's
# concatenations ([upsampled deeper part, skip part]) map each part's old channels to the front of
# that part. The result is a width-W2 state dict for train_pick.py's PICK_INIT.
# Usage: widen.py IN.pt W2 OUT.pt   (the torch venv)
import os, sys
import torch

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../pick-1"))
import train_pick as tp

src = torch.load(sys.argv[1])
w2, out_path = int(sys.argv[2]), sys.argv[3]
w = src["e0.0.0.weight"].shape[0]
inputs = src["e0.0.0.weight"].shape[1]
torch.manual_seed(0)
fresh = tp.UNet(inputs, w2).state_dict()
out = {}
for name, sources in tp.UNET_LAYERS:
    old_w, old_b = src[name + ".weight"], src[name + ".bias"]
    new_w, new_b = fresh[name + ".weight"].clone(), fresh[name + ".bias"].clone()
    o_old = old_w.shape[0]
    if sources is None:
        old_in = torch.arange(old_w.shape[1])
    else:
        parts, at_new = [], 0
        for s in sources:
            parts.append(torch.arange(src[s + ".weight"].shape[0]) + at_new)
            at_new += fresh[s + ".weight"].shape[0]
        old_in = torch.cat(parts)
        assert at_new == new_w.shape[1], (name, at_new, new_w.shape)
        new_in = torch.ones(new_w.shape[1], dtype=torch.bool)
        new_in[old_in] = False
        new_w[:, new_in] = 0.0  # nothing reads a new channel yet
    new_w[:o_old, old_in] = old_w
    new_b[:o_old] = old_b
    if name == "head":
        assert new_w.shape[0] == o_old
    out[name + ".weight"], out[name + ".bias"] = new_w, new_b
assert set(out) == set(fresh)
torch.save(out, out_path)
# The grown network answers as the trained one.
x = torch.randn(1, inputs, 64, 128)
a, b = tp.UNet(inputs, w), tp.UNet(inputs, w2)
a.load_state_dict(src); b.load_state_dict(out)
with torch.no_grad():
    diff = (a(x) - b(x)).abs().max().item()
print(f"width {w} -> {w2}: {sum(v.numel() for v in out.values())} parameters; max difference {diff:.2e}")
assert diff < 1e-4
