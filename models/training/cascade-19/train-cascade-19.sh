#!/usr/bin/env bash
# Cascade run 19: the coarse stage trained alone again (as cascade-17), now with the refinement
# spacing 2.5, 1.5 in the configuration (so validation scores the network as it will answer),
# from cascade-17's epoch 8, Adam 5e-5 for 7 epochs then 5e-6 for 3, 200 steps an epoch, seed 43.
# Why: cascade-17 moved the validation reference MAE (3.377 -> 3.262), the whole-network run
# cascade-18 at 2e-5 did not within 500 steps (3.239 -> 3.254-3.302), and a coarse-only step is
# twice as cheap.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/main/target/release/omnimvs}
RUN=${RUN:-/work/runs/cascade-19}
INIT=${INIT:-/work/main/models/training/cascade-17/epoch8.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --init "$INIT" \
  --train-only coarse --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00005 --lr-low 0.000005 --low-lr-epochs 3 --epochs 10 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 43 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
