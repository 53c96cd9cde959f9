#!/usr/bin/env python3
"""Reads one frame's output, the inverse-depth TIFF that `omnimvs sgm`, `omnimvs infer` and
the other examples write, and turns it into depth in metres (OUT/%05d_depth_m.tiff) and into
a point cloud in the rig's frame (OUT/%05d_points.ply: x, y, z in metres, binary), with
numpy alone.

    pip install tifffile numpy
    python examples/python/read_outputs.py OUT FRAME

The map is an equirectangular panorama around the rig, row-major, row 0 at the top. Column c
of a W-wide map looks at longitude theta = (c - W/2) / (W/2) * pi + pi/2, row r of an H-high
one at latitude phi = (r - (H-1)/2) / ((H-1)/2) * phi_max with phi_max = 180 H / W degrees
(square pixels: 45 for 160x640). The ray of a pixel in the rig frame (x right, y down,
z forward) is (-cos phi cos theta, sin phi, cos phi sin theta); the point is the ray divided
by the inverse depth.
"""

import argparse
from pathlib import Path

import numpy as np
import tifffile

FARTHEST_M = 1000.0  # points farther than this (sky) are left out of the cloud


def rays(height, width):
    """The unit ray of every pixel of a height x width panorama, shape (height, width, 3)."""
    phi_max = np.radians(180.0 * height / width)
    theta = (np.arange(width) - width / 2) / (width / 2) * np.pi + np.pi / 2
    phi = (np.arange(height) - (height - 1) / 2) / ((height - 1) / 2) * phi_max
    theta, phi = np.meshgrid(theta, phi)
    return np.stack([-np.cos(phi) * np.cos(theta), np.sin(phi), np.cos(phi) * np.sin(theta)], axis=-1)


def write_ply(path, xyz):
    """A binary little-endian PLY of float32 points."""
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(xyz)}\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.ascontiguousarray(xyz, dtype="<f4").tobytes())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="an output folder of omnimvs sgm / infer")
    parser.add_argument("frame", type=int)
    args = parser.parse_args()

    inv_depth = tifffile.imread(args.out / f"{args.frame:05d}.tiff")  # float32, 1/m
    height, width = inv_depth.shape
    print(f"{height}x{width} inverse depth, latitudes +-{180 * height / width:g} degrees")

    # 0 is at infinity (sky); NaN means no answer (e.g. `sgm --min-confidence`).
    with np.errstate(divide="ignore"):
        depth_m = np.where(inv_depth == 0, np.inf, 1.0 / inv_depth).astype(np.float32)
    tifffile.imwrite(args.out / f"{args.frame:05d}_depth_m.tiff", depth_m)
    ahead = depth_m[height // 2, width // 2]  # the middle column looks along +z
    near = depth_m[depth_m < FARTHEST_M]
    print(f"depth ahead {ahead:.2f} m; nearest {near.min():.2f} m, median {np.median(near):.2f} m; "
          f"{np.count_nonzero(depth_m >= FARTHEST_M)} pixels beyond 1 km (sky)")

    keep = depth_m < FARTHEST_M  # NaN compares False: left out too
    points = rays(height, width)[keep] * depth_m[keep][:, None]
    ply = args.out / f"{args.frame:05d}_points.ply"
    write_ply(ply, points)
    print(f"wrote {ply} ({len(points)} points)")


if __name__ == "__main__":
    main()
