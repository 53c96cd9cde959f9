#!/usr/bin/env python3
"""Golden values of the cross-camera photometric difference, from the independent NumPy reading
of the reference conventions (../shared/tools/omni_np.py, `consistency`), for the test
`crates/omnimvs-cli/tests/cli_photometric.rs`.

    omnimvs sgm ../shared/data/omnimvs-samples/itbt_sample --frames 1 --out /tmp/sgm-itbt1
    python3 scripts/photometric_golden/make_photometric_golden.py /tmp/sgm-itbt1/00001.tiff

prints the difference of the ZNCC+SGM depth map of itbt_sample frame 1 and of a constant 3 m.
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.join(HERE, "..", "..", "..", "shared")
sys.path.insert(0, os.path.join(SHARED, "tools"))
import omni_np  # noqa: E402

DATASET = os.path.join(SHARED, "data", "omnimvs-samples", "itbt_sample")


def main():
    pred = omni_np.read_f32_tiff(sys.argv[1])
    print(f"sgm      {omni_np.consistency(DATASET, 1, pred, 45.0)!r}")
    const = np.full_like(pred, np.float32(1.0 / 3.0))
    print(f"constant {omni_np.consistency(DATASET, 1, const, 45.0)!r}")


if __name__ == "__main__":
    main()
