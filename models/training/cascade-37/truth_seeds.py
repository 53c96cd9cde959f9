#!/usr/bin/env python3
"""Seeds for `--example cascade_seeded`: the truth at an H x W grid (nearest sample of the
ground truth, inverse depth in 1/m), one TIFF per frame, for the bound of a network whose
coarse stage sits on that grid (stop 35: 80 x 320).

    python3 truth_seeds.py DATASET A B H W OUT_DIR
"""
import os
import sys

import numpy as np
import tifffile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o  # noqa: E402

ds, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
h, w, out = int(sys.argv[4]), int(sys.argv[5]), sys.argv[6]
os.makedirs(out, exist_ok=True)
for f in range(a, b + 1):
    truth = o.gt_for_output(ds, f, h, w, 45.0)
    tifffile.imwrite(f"{out}/{f:05d}.tiff", truth.astype(np.float32))
print(f"{out}: {b - a + 1} seeds at {h} x {w}")
