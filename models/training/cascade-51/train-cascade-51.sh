#!/usr/bin/env bash
# Cascade run 51 (stop 38): cascade-47 e4 with the full stage's hypotheses 1.75 index units apart
# (`--stage-intervals 2.5,1.75`; alone a hair better than 1.5 on every validation set, see
# ../cascade-49/README.md), its full-resolution stage trained alone (`--train-only fine`: the regulariser with the stride-2 projection), after the half stage alone gave nothing (cascade-50),
# for the house figures that keep it from being bundled (hard house >1 / >3 / >5 about 1.5 points
# worse than the bundled network's). The mix and validation of cascade-45; Adam 1e-4 for 3 epochs
# of 150 steps, then 1e-5 for 1; seed 165. Resumable: rerun this script.
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs}
RUN=${RUN:-/work/runs/cascade-51}
INIT=${INIT:-/work/main/models/training/cascade-47/best.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.75 \
  --coarse-scale 2 --coarse-spheres 16 --coarse-stride4 on --same-grid-selector on \
  --coarse-squeeze 64 \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" --train-only fine \
  --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.0001 --lr-low 0.00001 --low-lr-epochs 1 --epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106,/work/data/house-hard-s107 \
  --val-frames 481..500 --max-val-frames 60 --seed 165 --max-steps 150 \
  --column-window 160 --photometric on --out "$RUN"
