#!/usr/bin/env python3
"""Start the photometric cue's weights of a cascade at the scale of one correlation group.

A network grown into the cue (`omnimvs train --init W --zncc-cue on`) starts with the cue's
input weights at zero; at Adam's 1e-4 they were still 20x smaller than the correlation groups'
after 400 steps (cascade-8), so the cue hardly spoke. Here, in every stage's first convolution
(input channels `c * K + k`: the G correlation groups, the visibility, then the cue, K hypotheses
each), the cue's weights for hypothesis k become alpha times the mean of the G groups' weights
for k, alpha the ratio of the correlation's standard deviation to the cue's on training frames
(`cargo run --release -p omnimvs-train --example cue_scale`): the cue enters as one more group
of similarity, voting as the average group votes.

usage: init_cue.py IN.safetensors OUT.safetensors ALPHA_COARSE ALPHA_HALF ALPHA_FULL
(the configuration JSON beside IN is copied beside OUT; numpy only)
"""
import json
import shutil
import struct
import sys

import numpy as np

# (tensor, configuration key of its hypotheses, index into `groups`)
STAGES = [
    ("coarse.c0.0.conv.weight", lambda p: p["coarse_spheres"], 2),
    ("mid.convs.0.conv.weight", lambda p: p["stage_hypotheses"][0], 1),
    ("fine.convs.0.conv.weight", lambda p: p["stage_hypotheses"][1], 0),
]


def main():
    src, dst = sys.argv[1], sys.argv[2]
    alphas = [float(a) for a in sys.argv[3:6]]
    config = json.load(open(src[: -len(".safetensors")] + ".json"))
    params = config["cascade"]
    assert params.get("zncc_cue"), "the network has no photometric cue (train --zncc-cue on)"
    raw = bytearray(open(src, "rb").read())
    n = struct.unpack("<Q", raw[:8])[0]
    header = json.loads(raw[8 : 8 + n])
    for (name, hyps, level), alpha in zip(STAGES, alphas):
        k, g = hyps(params), params["groups"][level]
        entry = header[name]
        assert entry["dtype"] == "F32", entry
        start, end = (8 + n + o for o in entry["data_offsets"])
        w = np.frombuffer(bytes(raw[start:end]), dtype=np.float32).reshape(entry["shape"]).copy()
        assert w.shape[1] == (g + 2) * k, (name, w.shape, g, k)
        groups = w[:, : g * k].reshape(w.shape[0], g, k, *w.shape[2:])
        w[:, (g + 1) * k :] = alpha * groups.mean(axis=1)
        raw[start:end] = w.astype(np.float32).tobytes()
        print(f"{name}: cue weights mean |w| {np.abs(w[:, (g + 1) * k:]).mean():.4f}, "
              f"groups' {np.abs(groups).mean():.4f} (alpha {alpha})")
    with open(dst + ".tmp", "wb") as f:
        f.write(raw)
    shutil.move(dst + ".tmp", dst)
    shutil.copy(src[: -len(".safetensors")] + ".json", dst[: -len(".safetensors")] + ".json")


if __name__ == "__main__":
    main()
