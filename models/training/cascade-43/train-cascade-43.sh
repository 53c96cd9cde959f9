#!/usr/bin/env bash
# Cascade run 43 (stop 36): cascade-42's best (cascade-40 epoch 2 with the half stage's learnt
# choice among the 3 x 3 coarse answers around each pixel, the selector trained alone) trained
# as a whole, so that the half stage and the features adapt to the chosen centres. Adam 2e-5,
# epochs of 100 steps, the mix of cascade-40 (../cascade-41/gen-data.sh); seed 153.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs}
RUN=${RUN:-/work/runs/cascade-43}
INIT=${INIT:-/work/main/models/training/cascade-42/best.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on --same-grid-selector on \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00002 --lr-low 0.000005 --low-lr-epochs 1 --epochs 6 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 153 --max-steps 100 \
  --column-window 160 --photometric on --out "$RUN"
