#!/usr/bin/env bash
# SweepNet-style cost, run sweepnet-2 (issue 15). Resumable: omnimvs train --resume /work/runs/sweepnet-2
set -euo pipefail
/work/bin/omnimvs-sweep2 train --cost sweepnet --data /work/data/things-s101,/work/data/house-s102 \
  --out /work/runs/sweepnet-2 --steps 3000 --batch 256 --lr 0.001 \
  --train-frames 1..480 --val-frames 481..500 --seed 1
