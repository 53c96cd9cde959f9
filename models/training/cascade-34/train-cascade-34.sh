#!/usr/bin/env bash
# Cascade run 34: as cascade-33 (the full-resolution stage alone grown into two neighbour
# hypotheses per pixel, the lowest and highest centre of the 9 x 9 pixels around it,
# `--neighbour-hypotheses 0,4`, Adam 3e-5), with the two starting at a score of -2 instead of -5
# (`--neighbour-start-score -2`, stop 33): in cascade-33 they still carried 0.4-0.5 % of each
# pixel's weight after 300 steps, the softmax passing them almost no gradient. Starts from the
# bundled cascade-25 epoch 4; 2 epochs of 300 steps; seed 109.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c34}
RUN=${RUN:-/work/runs/cascade-34}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 --neighbour-hypotheses 0,4 \
  --neighbour-start-score -2 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only fine --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00003 --lr-low 0.000003 --low-lr-epochs 0 --epochs 2 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 109 --max-steps 300 \
  --column-window 160 --photometric on --out "$RUN"
