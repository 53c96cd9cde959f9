#!/usr/bin/env bash
# Cascade run 39: cascade-38 epoch 5 (the coarse stage on the half-resolution grid, also
# correlating the stride-4 features) with its half stage trained alone (`--train-only mid`)
# for the centres it now gets: the coarse answer itself, where the half stage was trained on
# the learnt upsampling of a 40 x 160 answer. Adam 5e-5 for 3 epochs of 200 steps, then 5e-6
# for 1; seed 139.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c38}
RUN=${RUN:-/work/runs/cascade-39}
INIT=${INIT:-/work/main/models/training/cascade-38/epoch5.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only mid --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00005 --lr-low 0.000005 --low-lr-epochs 1 --epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 139 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
