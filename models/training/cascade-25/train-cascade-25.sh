#!/usr/bin/env bash
# Cascade run 25: the GPU run of stop 31 (coarse stage alone with the aggregated coarse cue,
# `--coarse-cue-sgm on`, from cascade-23 e9, Adam 1e-4, 2,400 steps on 480 frames:
# docs/gpu/2026-11-26-h200-stop31, its best epoch 11 = INIT) polished on the CPU at low rates
# over the whole training mix: the coarse stage alone, Adam 1e-5 for 2 epochs of 200 steps,
# then 2 at 1e-6; seed 71. Same settings as cascade-23 and -24 otherwise. Started in stop 31.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c24}
RUN=${RUN:-/work/runs/cascade-25}
INIT=${INIT:-/work/main/docs/gpu/2026-11-26-h200-stop31/best.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only coarse --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.00001 --lr-low 0.000001 --low-lr-epochs 2 --epochs 4 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 71 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
