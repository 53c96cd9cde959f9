#!/usr/bin/env bash
# Cascade run 48 (stop 37): cascade-47's best (cascade-45's coarse stage, trained with hard house
# frames of the published rig, squeezed to 64 channels, and the half grid's selector retrained)
# trained as a whole at a low rate, so that the features and refinement stages follow the
# coarse stage the new mix made (house >1 / >3 / >5 were still worse than the bundled
# network's). Adam 1e-5 for 3 epochs of 100 steps, then 2e-6 for 1; the mix and validation of
# cascade-45; seed 160. Resumable: rerun this script.
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs}
RUN=${RUN:-/work/runs/cascade-48}
INIT=${INIT:-/work/main/models/training/cascade-47/best.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on --same-grid-selector on \
  --coarse-squeeze 64 \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00001 --lr-low 0.000002 --low-lr-epochs 1 --epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106,/work/data/house-hard-s107 \
  --val-frames 481..500 --max-val-frames 60 --seed 160 --max-steps 100 \
  --column-window 160 --photometric on --out "$RUN"
