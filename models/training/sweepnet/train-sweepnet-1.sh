#!/usr/bin/env bash
# SweepNet-style cost, run sweepnet-1 (issue 15). Resumable: omnimvs train --resume /work/runs/sweepnet-1
set -euo pipefail
/work/bin/omnimvs-sweep1 train --cost sweepnet --data /work/data/things-s101,/work/data/house-s102 \
  --out /work/runs/sweepnet-1 --steps 3000 --batch 256 --lr 0.001 \
  --train-frames 1..480 --val-frames 481..500 --seed 1
