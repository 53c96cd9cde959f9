#!/usr/bin/env bash
# Cascade run 26: cascade-25 epoch 4 (bundled in stop 31: the aggregated coarse cue) trained on
# as the coarse stage alone at a middle rate over the whole training mix, to see whether the
# CPU's longer data (1,150 frames against the GPU run's 480) still moves it: Adam 3e-5 for 5
# epochs of 200 steps, then 2 at 3e-6; seed 73. Same settings as cascade-25 otherwise.
# Started in stop 31.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c26}
RUN=${RUN:-/work/runs/cascade-26}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only coarse --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00003 --lr-low 0.000003 --low-lr-epochs 2 --epochs 7 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 73 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
