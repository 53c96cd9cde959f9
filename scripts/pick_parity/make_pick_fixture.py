# Fixtures of crates/omnimvs-net/tests/pick.rs: the learnt pick's U-Net and its inputs as the
# scripts that train the picks compute them (scripts/pick/).
#   1. pick_tiny.safetensors: a U-Net of width 2 for one camera (11 inputs), seeded random weights
#      (the head too); io.safetensors: a random input (11, 16, 64), its logits, an index map and
#      the softmax-weighted candidates (the pick's answer).
#   2. inputs.safetensors: the 29 inputs on the real itbt_sample frame 1 for a synthetic answer and
#      spread (formulas below, repeated in the test) at every 97th pixel of 160 x 640.
#   3. (a wider layout: pick-3's) pick_tiny3.safetensors / io3.safetensors: as 1. with eleven
#      candidates (radii 1, 2, 4, 7, 12) and the layout in the metadata, one camera (depth radii
#      2, 12 and ZNCC: 8 + 10 + 10 = 28 inputs); inputs3.safetensors: as 2. with depth radii 2, 12
#      and ZNCC over 5 x 5 (58 inputs).
# Usage (a venv with torch, numpy, scipy, pillow, tifffile, pyyaml; omni_np.py on PYTHONPATH or
# named by OMNI_NP, as scripts/pick/pick_inputs.py needs it):
#   make_pick_fixture.py OUT_DIR [SAMPLES_DIR]
import json, os, struct, sys
import numpy as np, torch

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "pick"))
import train_pick as tp
import pick_inputs as pi


def write(path, tensors):
    header, off = {}, 0
    for k, a in tensors.items():
        a = np.ascontiguousarray(a, dtype="<f4")
        tensors[k] = a
        header[k] = {"dtype": "F32", "shape": list(a.shape), "data_offsets": [off, off + a.nbytes]}
        off += a.nbytes
    h = json.dumps(header).encode()
    h += b" " * ((8 - len(h) % 8) % 8)
    with open(path, "wb") as f:
        f.write(struct.pack("<Q", len(h))); f.write(h)
        for a in tensors.values():
            f.write(a.tobytes())


def synthetic_answer(h, w):
    """An answer with smooth parts and steps (float32), and a spread, as the test builds them."""
    r, c = np.meshgrid(np.arange(h, dtype=np.float64), np.arange(w, dtype=np.float64), indexing="ij")
    v = 40.0 + 30.0 * np.sin(c / 50.0) + 10.0 * np.cos(r / 17.0) + np.where((c % 160) >= 80, 50.0, 0.0)
    spread = 0.1 * r + 0.01 * c
    return v.astype(np.float32), spread.astype(np.float32)


def random_pick(out, weights_name, io_name, seed, channels, size, metadata=None):
    """A U-Net of width 2 with seeded random weights (tp.K candidates) and, for a random input of
    `channels` x `size`, its logits, a random index map and the pick's answer."""
    torch.manual_seed(seed)
    net = tp.UNet(channels, 2)
    with torch.no_grad():
        for p in net.parameters():
            p.copy_(torch.randn_like(p) * 0.3)
    tp.save_safetensors(net, os.path.join(out, weights_name), metadata)
    x = torch.randn(1, channels, *size)
    index = (torch.rand(1, *size) * 191.0).numpy().astype(np.float32)
    with torch.no_grad():
        logits = net(x)
        ans = tp.answer(logits, torch.as_tensor(tp.cands(index)))
    write(os.path.join(out, io_name), {"input": x[0].numpy(), "logits": logits[0].numpy(),
                                       "index": index[0], "answer": ans[0].numpy()})


def main():
    out = sys.argv[1]
    samples = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, "../../../shared/data/omnimvs-samples")
    os.makedirs(out, exist_ok=True)
    random_pick(out, "pick_tiny.safetensors", "io.safetensors", 7, 11, (16, 64))
    # pick-3's layout.
    tp.RADII, tp.K = (1, 2, 4, 7, 12), 11
    random_pick(out, "pick_tiny3.safetensors", "io3.safetensors", 8, 28, (32, 64),
                {"candidate_radii": "1,2,4,7,12", "depth_radii": "2,12", "zncc": "5"})

    ds = os.path.join(samples, "itbt_sample")
    o = pi.omni_np()
    cfg, cams, md = o.load(ds)
    min_inv = 1.0 / (1.0 / o.EPS)
    step = (1.0 / md - min_inv) / 191.0
    v, spread = synthetic_answer(160, 640)
    ims = pi.normalised_images(ds, 1, cfg, cams)
    at = np.arange(0, 160 * 640, 97)
    for name, radii, k in (("inputs.safetensors", (2,), 0), ("inputs3.safetensors", (2, 12), 5)):
        feats = pi.features(ims, cams, v.astype(np.float64), spread.astype(np.float64), min_inv, step,
                            depth_radii=radii, zncc_k=k)
        write(os.path.join(out, name),
              {"pixels": at.astype(np.float32), "inputs": feats.reshape(feats.shape[0], -1)[:, at]})
    print("wrote", out)


if __name__ == "__main__":
    main()
