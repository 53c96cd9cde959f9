#!/usr/bin/env python3
"""360-degree depth of a real frame with omnimvs from Python: the classical method
(ZNCC + SGM) and the default bundled network (the cascade), side by side in one matplotlib
figure with the camera images.

    pip install ./crates/omnimvs-py matplotlib
    python examples/python/itbt_demo.py DATASET [--frame 1] [--out itbt_demo.png]

DATASET is a folder with config.yaml and the cameras' images, e.g. the reference
implementation's real sample `itbt_sample` (four cameras, three frames).
"""

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # write a file; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import omnimvs  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path, help="dataset folder (with config.yaml)")
    parser.add_argument("--frame", type=int, default=1)
    parser.add_argument("--out", type=Path, default=Path("itbt_demo.png"))
    args = parser.parse_args()

    ds = omnimvs.Dataset(args.dataset)
    print(f"{ds}: frames {ds.frames}")
    images = ds.images(args.frame)

    t0 = time.perf_counter()
    sgm = omnimvs.sgm(ds, args.frame)  # 160x640, N = 192, inverse depth (1/m)
    t1 = time.perf_counter()
    net = omnimvs.infer(ds, args.frame)  # the bundled cascade network (the default), 160x640
    t2 = time.perf_counter()
    print(f"ZNCC+SGM {sgm.shape} in {t1 - t0:.1f} s, network {net.shape} in {t2 - t1:.1f} s")

    vmax = 1.0 / ds.min_depth  # the nearest sphere; colours are comparable across panels
    fig = plt.figure(figsize=(12, 7.5), layout="constrained")
    grid = fig.add_gridspec(3, len(images))
    for k, image in enumerate(images):
        ax = fig.add_subplot(grid[0, k])
        ax.imshow(image, cmap="gray")
        ax.set_title(f"camera {k + 1}")
        ax.axis("off")
    extent = (-180, 180, -45, 45)  # longitude, latitude in degrees (row 0 is the top)
    for row, (name, inv_depth) in enumerate([("ZNCC + SGM", sgm), ("bundled network (cascade)", net)], 1):
        ax = fig.add_subplot(grid[row, :])
        shown = ax.imshow(inv_depth, cmap="turbo", vmin=0, vmax=vmax, extent=extent, aspect="auto",
                          interpolation="nearest")
        ax.set_title(f"{name}: inverse depth, {inv_depth.shape[0]}x{inv_depth.shape[1]}, "
                     f"median depth {np.median(1 / np.maximum(inv_depth, 1e-6)):.2f} m")
        ax.set_xlabel("longitude (deg)")
        ax.set_ylabel("latitude (deg)")
        fig.colorbar(shown, ax=ax, label="1/m")
    fig.suptitle(f"{args.dataset.name}, frame {args.frame}")
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
