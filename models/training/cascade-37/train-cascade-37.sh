#!/usr/bin/env bash
# Cascade run 37: the coarse stage moved to the half-resolution grid (`--coarse-scale 2`: 80 x
# 320 at the paper's grid) over 16 spheres, its cue matched on its own grid from the half-size
# images at three depths per sphere (`--coarse-cue-oversample 1 --coarse-cue-depths 3`), the
# half stage centred on the coarse answer itself (stop 35). From the bundled cascade-25 epoch
# 4: the coarse stage's first and scoring convolutions resampled from 32 spheres to 16
# (`CascadeNet::with_coarse_grid`), every other weight as it was; then the coarse stage
# trained alone (`--train-only coarse`: the stride-8 feature branch and the coarse
# regulariser, the coarse loss only). Adam 1e-4, epochs of 200 steps; seed 131.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c37}
RUN=${RUN:-/work/runs/cascade-37}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-scale 2 --coarse-spheres 16 \
  --coarse-cue-oversample 1 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only coarse --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.0001 --lr-low 0.00001 --low-lr-epochs 2 --epochs 12 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 131 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
