#!/usr/bin/env python3
"""How far each method's answer lies from the truth, as a refinement stage would see it: the
share of reference-scored pixels (sky not scored) within the cascade's half-stage reach
(+-7.5 index units of N = 192: 8 hypotheses 2 apart, plus half a step) and its full-stage reach
(+-2.5), frames 1-20 at 160x640, per output folder; and, for every pair, the share where at
least one of the two is within reach (what a refinement seeded by both could start from).
Reads the outputs through ../cascade-10/error_by_depth.py's `signed_errors` (omni_np.py's
reference ground truth and resampling).

    python3 seed_reach.py DATASET OUTDIR [OUTDIR ...]

Stop 25 ran it in /work/eval on the held-out things set:
    seed_reach.py /work/data/test-things-s7001 sgm-test-things-s7001 c10e14-test-things-s7001
"""
import itertools
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "../cascade-10"))
from error_by_depth import signed_errors  # noqa: E402

REACHES = [2.5, 7.5]


def main():
    ds, outs = sys.argv[1], sys.argv[2:]
    errs = {m: [] for m in outs}
    for _, errors in signed_errors(ds, outs):
        for m in outs:
            errs[m].append(np.abs(errors[m]))
    errs = {m: np.concatenate(e) for m, e in errs.items()}
    for m, e in errs.items():
        cells = " ".join(f"within {r}: {100 * (e <= r).mean():.1f}%" for r in REACHES)
        print(f"{m}: {e.size} pixels, MAE {e.mean():.2f}; {cells}")
    for a, b in itertools.combinations(outs, 2):
        ea, eb = errs[a], errs[b]
        cells = " ".join(f"within {r}: {100 * ((ea <= r) | (eb <= r)).mean():.1f}%"
                         for r in REACHES)
        print(f"{a} or {b}: {cells}; per-pixel better of the two MAE "
              f"{np.minimum(ea, eb).mean():.2f}")


if __name__ == "__main__":
    main()
