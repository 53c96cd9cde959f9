#!/usr/bin/env python3
"""The bundled network on a dataset folder: the default `cascade` (160x640, N = 192, with its
learnt picks after it) or the small `tiny` (the paper's network, 32x128, N = 64); the weights
are compiled into the package and it runs on the CPU. Writes per frame OUT/%05d.tiff (float32
inverse depth, 1/m), %05d_index.tiff (hypothesis index) and %05d_entropy.tiff (how unsure
each pixel is, nats), as `omnimvs infer` names them, and prints the paper's metrics of the
frames that have ground truth.

    pip install ./crates/omnimvs-py tifffile
    python examples/python/bundled_network.py DATASET OUT [--frames A..B] [--model tiny]

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
    parser.add_argument("--model", default="cascade", choices=["cascade", "tiny"])
    args = parser.parse_args()

    ds = omnimvs.Dataset(args.dataset)
    args.out.mkdir(parents=True, exist_ok=True)
    for frame in frame_list(args.frames, ds):
        t0 = time.perf_counter()
        # `weights=` takes a bundled model's name or a .safetensors file of `omnimvs train`;
        # `maps=True` returns every map instead of the inverse depth alone.
        maps = omnimvs.infer(ds, frame, weights=args.model, maps=True)
        seconds = time.perf_counter() - t0
        inv_depth = maps["inv_depth"]
        tifffile.imwrite(args.out / f"{frame:05d}.tiff", inv_depth)
        tifffile.imwrite(args.out / f"{frame:05d}_index.tiff", maps["index"])
        if maps["entropy"] is not None:
            tifffile.imwrite(args.out / f"{frame:05d}_entropy.tiff", maps["entropy"])
        line = f"frame {frame}: {inv_depth.shape} in {seconds:.2f} s"
        line += f", median depth {np.median(1 / np.maximum(inv_depth, 1e-6)):.2f} m"
        if ds.ground_truth(frame) is not None:
            # Scored on the paper's 160x640 grid (a 32x128 answer is resampled to it).
            m = omnimvs.evaluate(inv_depth, ds, frame)
            line += f", MAE {m['mae']:.2f} % of N, >3 {m['over3_pct']:.1f} %"
        print(line)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
