#!/usr/bin/env python3
"""Each stage's signed and absolute error by where the truth falls between two coarse spheres
(its phase: true index modulo the sphere spacing, in eighths), for `cascade_dump` folders, on
valid pixels with true index 60-175 (house walls and floors): a coarse stage whose soft argmax
snapped toward its spheres would show a sawtooth here (stop 37: none, on house frames).

    python3 sphere_phase.py A B SPACING DUMP_DIR...
"""
import os, sys, numpy as np
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from studylib import dump_frame
def up(m, shape):
    fy, fx = shape[0] // m.shape[0], shape[1] // m.shape[1]
    return np.kron(m, np.ones((fy, fx), dtype=m.dtype))
a, b, sp = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
for d in sys.argv[4:]:
    E = {k: [] for k in ("coarse", "half", "full")}; T = []
    for f in range(a, b + 1):
        _, get = dump_frame(d, f)
        gt, valid = get("gt"), get("valid") > 0.5
        ok = valid & (gt > 60) & (gt < 175)
        for k in E: E[k].append((up(get(k), gt.shape) - gt)[ok])
        T.append(gt[ok])
    t = np.concatenate(T); ph = (t % sp) / sp
    print(d)
    for i in range(8):
        m = (ph >= i / 8) & (ph < (i + 1) / 8)
        print(f"  phase {i/8:.3f} {100*m.mean():4.1f}% " + "  ".join(f"{k} {np.concatenate(v)[m].mean():+5.2f} |{np.abs(np.concatenate(v)[m]).mean():4.2f}|" for k, v in E.items()))
