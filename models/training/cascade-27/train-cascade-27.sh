#!/usr/bin/env bash
# Cascade run 27: a second cue channel for the half-resolution stage, the coarse cue's
# half-grid planes aggregated by semi-global matching (P1 0.1, P2 2.0) and read at each pixel's
# hypotheses (`--mid-cue-sgm on`), then the half stage's regulariser trained alone
# (`--train-only mid`) from the bundled cascade-25 epoch 4 to read it (its new input weights
# start at zero: the start answers as cascade-25 e4). Why: on the half grid, the aggregated cue
# alone is off by more than 3 at 6.6-9.1 % of far open pixels where the network is at 21.1 %
# (../cascade-25/half_study.py). Adam 5e-5 for 4 epochs of 200 steps, then 2 at 5e-6; seed 79.
# Started in stop 31.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c27}
RUN=${RUN:-/work/runs/cascade-27}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on --mid-cue-sgm on \
  --init "$INIT" \
  --train-only mid --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00005 --lr-low 0.000005 --low-lr-epochs 2 --epochs 6 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 79 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
