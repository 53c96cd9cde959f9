#!/usr/bin/env python3
"""Held-out frames side by side at 160x640 (the paper's grid): the ground truth's inverse depth,
then for each method its inverse depth and its error in index units of N = 192 by the reference's
rules (sky and holes not scored: gray), with the frame's MAE (% of N) in the title.

Usage: heldout_panels.py OUT.png DATASET FRAME LABEL=OUTDIR [LABEL=OUTDIR ...]
  OUTDIR holds FRAME's inverse depth as `omnimvs infer` / `omnimvs sgm` write it (%05d.tiff).
Runs in the venv of ../../../shared/tools/omni_np.py (numpy, scipy, Pillow, matplotlib).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../shared/tools"))
import omni_np as o  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

N = 192


def main():
    if len(sys.argv) < 5:
        raise SystemExit(__doc__)
    out, ds, frame = sys.argv[1], sys.argv[2], int(sys.argv[3])
    methods = [a.split("=", 1) for a in sys.argv[4:]]
    _, _, min_depth = o.load(ds)
    gt = o.gt_reference(ds, frame, 160, 640, 45.0)
    if gt is None:
        raise SystemExit(f"{ds}: no ground truth for frame {frame}")
    gi, valid, min_inv, step = o.reference_gt_index(gt, min_depth, N)
    vmax = 1.0 / min_depth
    rows = 1 + 2 * len(methods)
    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.25 * rows))
    axes[0].imshow(np.where(gt > 0, gt, 0), cmap="magma", vmin=0, vmax=vmax)
    axes[0].set_title(f"{os.path.basename(ds.rstrip('/'))} frame {frame}: ground truth, inverse depth "
                      f"(0 to {vmax:.2f} 1/m, near = bright)", fontsize=9)
    for k, (label, d) in enumerate(methods):
        pred = o.read_f32_tiff(os.path.join(d, f"{frame:05d}.tiff"))
        if pred.shape != (160, 640):
            pred = o.upsample(pred, 160, 640)
        idx = (pred.astype(np.float64) - min_inv) / step
        ok = valid & np.isfinite(idx)
        err = np.abs(idx - gi)
        mae = err[ok].mean() / N * 100
        ax = axes[1 + 2 * k]
        ax.imshow(pred, cmap="magma", vmin=0, vmax=vmax)
        ax.set_title(f"{label}: inverse depth", fontsize=9)
        ax = axes[2 + 2 * k]
        shown = np.ma.masked_where(~ok, err)
        cmap = plt.get_cmap("inferno").copy()
        cmap.set_bad("0.6")
        ax.imshow(shown, cmap=cmap, vmin=0, vmax=30)
        ax.set_title(f"{label}: error, index units of N = 192 (0 to 30+; gray: not scored); "
                     f"frame MAE {mae:.2f} % of N", fontsize=9)
    for ax in axes:
        ax.set_xticks([]); ax.set_yticks([])
    fig.tight_layout(pad=0.3)
    tmp = out + ".tmp.png"
    fig.savefig(tmp, dpi=80)
    from PIL import Image  # a 256-colour palette: a third of the bytes, no visible change
    Image.open(tmp).convert("RGB").quantize(256).save(tmp, optimize=True)
    os.replace(tmp, out)
    print(out)


if __name__ == "__main__":
    main()
