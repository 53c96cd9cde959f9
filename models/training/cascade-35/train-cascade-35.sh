#!/usr/bin/env bash
# Cascade run 35: as cascade-34 (the full-resolution stage alone grown into two neighbour
# hypotheses per pixel, the lowest and highest centre of the 9 x 9 pixels around it,
# `--neighbour-hypotheses 0,4`, Adam 3e-5), with a rate of their own for the weights grown for
# them: `--neighbour-gain 30` multiplies their evidence and scores by 30, so under Adam those
# weights train 30 times faster (9e-4) than the rest of the stage (stop 34; in cascade-33/34
# the zero-started weights could move by about 0.02 in 600 steps). Starting score -3.
# Starts from the bundled cascade-25 epoch 4; epochs of 400 steps; seed 113.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c35}
RUN=${RUN:-/work/runs/cascade-35}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 --neighbour-hypotheses 0,4 \
  --neighbour-start-score -3 --neighbour-gain 30 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only fine --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00003 --lr-low 0.000003 --low-lr-epochs 0 --epochs 12 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 113 --max-steps 400 \
  --column-window 160 --photometric on --out "$RUN"
