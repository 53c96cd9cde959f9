#!/usr/bin/env bash
# Cascade run 41 (stop 36): cascade-40 epoch 2 (the coarse stage on the half-resolution grid,
# correlating the stride-4 features too, trained as a whole for 200 steps) trained further as a
# whole, the step stop 35 left for the next session. Adam 2e-5, epochs of 150 steps, the same
# mix as cascade-40 (regenerated on a fresh machine, frames 1-100 of each set:
# gen-data.sh here); seed 151.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs}
RUN=${RUN:-/work/runs/cascade-41}
INIT=${INIT:-/work/main/models/training/cascade-40/epoch2.safetensors}
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
  --optimizer adam --lr 0.00002 --lr-low 0.000005 --low-lr-epochs 2 --epochs 10 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 151 --max-steps 150 \
  --column-window 160 --photometric on --out "$RUN"
