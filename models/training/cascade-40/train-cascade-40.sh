#!/usr/bin/env bash
# Cascade run 40: cascade-38 epoch 5 (the coarse stage on the half-resolution grid, also
# correlating the stride-4 features) trained as a whole (every weight, all stages' losses), so
# that the half stage and the features adapt together to the finer coarse answer (stop 35:
# the half stage alone did not, cascade-39). Adam 2e-5, epochs of 100 steps; seed 149.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c38}
RUN=${RUN:-/work/runs/cascade-40}
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
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00002 --lr-low 0.000002 --low-lr-epochs 1 --epochs 5 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 149 --max-steps 100 \
  --column-window 160 --photometric on --out "$RUN"
