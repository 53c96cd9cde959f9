#!/usr/bin/env bash
# Cascade run 24: a second coarse cue channel, the photometric cue aggregated by semi-global
# matching over the coarse grid (`--coarse-cue-sgm on`: its 96 planes in depth order, 8
# wrapping paths, P1 0.05, P2 1.0; each sphere's excess cost over the pixel's best), then the
# coarse stage trained alone from the bundled cascade-23 epoch 9 to read it (its new input
# weights start at zero: the start answers as cascade-23 e9). Why: on things validation frames
# 481-490 the aggregated cue's best sphere lies within +-9 of the truth for 93.9-96.9 % of far
# pixels 12 or more from an edge, where the network answers within +-9 for 83.0 % and the raw
# cue for 78.8 % (sgm_cue.py). Same settings as cascade-23 otherwise. Epochs of 200 steps, Adam
# 5e-5, the last 3 at 5e-6; seed 67. Started in stop 31.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c24}
RUN=${RUN:-/work/runs/cascade-24}
INIT=${INIT:-/work/main/models/training/cascade-23/epoch9.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only coarse --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00005 --lr-low 0.000005 --low-lr-epochs 3 --epochs 12 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 67 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
