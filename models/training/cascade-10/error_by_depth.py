#!/usr/bin/env python3
"""Reference-protocol error by ground-truth depth: for each method's output folder, the MAE and
the mean signed error (bias; negative = answered too far) in % of N over the scored pixels whose
ground-truth index (N = 192) falls in each bin, frames 1-20, at 160x640. Uses
../shared/tools/omni_np.py for the reference's ground truth and resampling.

    python3 error_by_depth.py DATASET OUTDIR [OUTDIR ...]

How stop 24 found where cascade-10 lost on things (run in /work/eval):
    error_by_depth.py /work/data/test-things-s7001 sgm-test-things-s7001 \
        cascade9e1-test-things-s7001 c10e4-test-things-s7001
"""
import glob
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "../../../../shared/tools"))
sys.path.insert(0, "/work/shared/tools")
import omni_np as o  # noqa: E402

BINS = [0, 10, 20, 40, 80, 193]


def signed_errors(ds, outs, frames=range(1, 21)):
    """Per frame of `ds` (160x640, N = 192, the reference's ground truth and scored pixels):
    the ground-truth index of the scored pixels and, per output folder of `outs`, the signed
    index error (prediction - truth) there. Also used by ../cascade-11/seed_reach.py."""
    _, _, min_depth = o.load(ds)
    for f in frames:
        gt = o.gt_reference(ds, f, 160, 640, 45.0)
        gi, valid, min_inv, step = o.reference_gt_index(gt, min_depth)
        errors = {}
        for m in outs:
            cand = [p for p in glob.glob(os.path.join(m, f"{f:05d}*.tif*"))
                    if "entropy" not in p and "index" not in p and "conf" not in p]
            pred = o.upsample(o.read_f32_tiff(sorted(cand, key=len)[0]), 160, 640)
            pi = (pred.astype(np.float64) - min_inv) / step
            errors[m] = (pi - gi)[valid]
        yield gi[valid], errors


def main():
    ds, outs = sys.argv[1], sys.argv[2:]
    err = {m: [[] for _ in BINS[:-1]] for m in outs}
    for gi, errors in signed_errors(ds, outs):
        for m in outs:
            for b in range(len(BINS) - 1):
                sel = (gi >= BINS[b]) & (gi < BINS[b + 1])
                err[m][b].append(errors[m][sel])
    for m in outs:
        cells = []
        for b in range(len(BINS) - 1):
            e = np.concatenate(err[m][b])
            cells.append(f"[{BINS[b]},{BINS[b + 1]}) n={e.size / 1e3:.0f}k "
                         f"MAE {np.abs(e).mean() / 192 * 100:.2f} bias {e.mean() / 192 * 100:+.2f}")
        print(m, " | ".join(cells))


if __name__ == "__main__":
    main()
