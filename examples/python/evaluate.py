#!/usr/bin/env python3
"""Scores an estimate against ground truth with the paper's metrics under the reference
implementation's protocol (sky not scored): the inverse-depth maps ESTIMATE_DIR/%05d.tiff
(float32, 1/m, on any equirectangular grid over +-45 degrees: what `omnimvs sgm`,
`omnimvs infer` and the zncc_sgm.py and bundled_network.py examples write) against the
dataset's ground truth.

    pip install ./crates/omnimvs-py tifffile
    python examples/python/evaluate.py DATASET ESTIMATE_DIR [--frames A..B]

Per pixel E = |n_hat - n*| / N * 100, n the index of the inverse depth among N = 192
hypotheses on the paper's 160x640 grid; a frame's figures are the shares of pixels with
E > 1, 3 and 5 %, the mean (MAE) and the RMS of E; the dataset's, the mean over its frames.
"""

import argparse
from pathlib import Path

import numpy as np
import tifffile

import omnimvs

FIELDS = ["over1_pct", "over3_pct", "over5_pct", "mae", "rms"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path, help="dataset folder with ground truth")
    parser.add_argument("estimates", type=Path, help="folder of %%05d.tiff inverse depth maps")
    parser.add_argument("--frames", help="A..B or a single frame (default: every frame with ground truth)")
    args = parser.parse_args()

    ds = omnimvs.Dataset(args.dataset)
    if args.frames:
        first, _, last = args.frames.partition("..")
        frames = list(range(int(first), int(last or first) + 1))
    else:
        frames = [f for f in ds.frames if ds.ground_truth(f) is not None]
    if not frames:
        raise SystemExit(f"{args.dataset}: no frame with ground truth")

    print("frame    >1 %    >3 %    >5 %     MAE     RMS")
    rows = []
    for frame in frames:
        prediction = tifffile.imread(args.estimates / f"{frame:05d}.tiff")
        # Resampled to the 160x640 evaluation grid when it is on another one;
        # protocol="with-sky" would score sky as index 0, as training does.
        m = omnimvs.evaluate(prediction, ds, frame, protocol="reference")
        rows.append([m[k] for k in FIELDS])
        print(f"{frame:5d} " + " ".join(f"{m[k]:7.2f}" for k in FIELDS))
    # Each frame weighs the same, as in the paper.
    print(" mean " + " ".join(f"{v:7.2f}" for v in np.mean(rows, axis=0)))


if __name__ == "__main__":
    main()
