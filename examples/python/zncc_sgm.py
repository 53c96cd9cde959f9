#!/usr/bin/env python3
"""ZNCC + SGM, the classical method of the OmniMVS paper's Table 3, on a dataset folder: no
network, no GPU. Writes OUT/%05d.tiff per frame (float32 inverse depth, 1/m, 160x640 over
+-45 degrees of latitude), the file `omnimvs sgm` writes, and prints the paper's metrics of the
frames that have ground truth.

    pip install ./crates/omnimvs-py tifffile
    python examples/python/zncc_sgm.py DATASET OUT [--frames A..B]

DATASET is a folder with config.yaml and the cameras' images (e.g. the reference
implementation's itbt_sample).
"""

import argparse
import time
from pathlib import Path

import numpy as np
import tifffile

import omnimvs


def frame_list(text, dataset):
    """`A..B` (inclusive) or one frame; None: every frame of the dataset."""
    if text is None:
        return dataset.frames
    first, _, last = text.partition("..")
    return list(range(int(first), int(last or first) + 1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path, help="dataset folder (with config.yaml)")
    parser.add_argument("out", type=Path, help="output folder")
    parser.add_argument("--frames", help="A..B or a single frame (default: all)")
    args = parser.parse_args()

    # Reads config.yaml only: the rig, the minimum depth, where the images are.
    ds = omnimvs.Dataset(args.dataset)
    args.out.mkdir(parents=True, exist_ok=True)
    for frame in frame_list(args.frames, ds):
        t0 = time.perf_counter()
        # The paper's sweep by default: 160x640, +-45 degrees, N = 192 hypotheses; the
        # penalties P1 = 0.1, P2 = 2.0. `height=`, `width=`, `ndepth=` change the sweep.
        inv_depth = omnimvs.sgm(ds, frame)
        seconds = time.perf_counter() - t0
        tifffile.imwrite(args.out / f"{frame:05d}.tiff", inv_depth)
        line = f"frame {frame}: {inv_depth.shape} in {seconds:.2f} s"
        line += f", median depth {np.median(1 / np.maximum(inv_depth, 1e-6)):.2f} m"
        if ds.ground_truth(frame) is not None:
            m = omnimvs.evaluate(inv_depth, ds, frame)  # the reference protocol
            line += f", MAE {m['mae']:.2f} % of N, >3 {m['over3_pct']:.1f} %"
        print(line)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
