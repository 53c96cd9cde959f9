#!/usr/bin/env python3
"""Renders a small synthetic dataset for a rig (random objects in a room or under a sky, with
exact ground truth), then scores ZNCC + SGM and the bundled network on it. The dataset is in
the reference layout, ready for `omnimvs train --data OUT` (training is not offered in Python:
see the command, or the Rust example train_own_rig).

    pip install ./crates/omnimvs-py
    python examples/python/synth_dataset.py OUT [--rig CONFIG_YAML] [--frames 3]

--rig is a reference config.yaml with your calibration and
`config.omnimvs_sweep_min_depth` (e.g. the reference implementation's
itbt_sample/config.yaml); the default is the published 4-camera rig.
"""

import argparse
import time
from pathlib import Path

import omnimvs


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="output folder (the dataset)")
    parser.add_argument("--rig", type=Path, help="a reference config.yaml (default: the published rig)")
    parser.add_argument("--frames", type=int, default=3, help="number of frames (default 3)")
    args = parser.parse_args()

    rig = omnimvs.Rig.from_config(args.rig) if args.rig else None
    t0 = time.perf_counter()
    # OUT/config.yaml, OUT/camN/%05d.png (8-bit gray fisheyes), OUT/omnidepth_gt_640/%05d.tiff
    # (float32 inverse depth, 320x640 over +-90 degrees, 0 = sky). `size` renders every
    # camera at another size (the same rays); frames already complete are skipped, and the
    # same seed gives the same files.
    ds = omnimvs.synth("things", args.out, frames=(1, args.frames), seed=0, rig=rig, size=(384, 400))
    print(f"rendered {len(ds.frames)} frames of {ds.num_cameras} cameras into {ds.root} "
          f"in {time.perf_counter() - t0:.1f} s")

    for frame in ds.frames:
        gt = ds.ground_truth(frame)
        sgm = omnimvs.sgm(ds, frame)
        net = omnimvs.infer(ds, frame)
        scores = {name: omnimvs.evaluate(inv_depth, ds, frame) for name, inv_depth in
                  [("ZNCC+SGM", sgm), ("network", net)]}
        print(f"frame {frame}: ground truth {gt.shape}, "
              + ", ".join(f"{name} MAE {m['mae']:.2f}" for name, m in scores.items()))


if __name__ == "__main__":
    main()
