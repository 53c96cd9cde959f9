#!/usr/bin/env bash
# Cascade run 28: the half grid's learnt upsampling selector (`up_mid`, convex upsampling of
# the coarse answers) trained alone (`--train-only upsampling`, which since stop 32 accepts a
# network with the half grid's selector only) from the bundled cascade-25 epoch 4. Why: two
# thirds of the things error lies within 4 px of a depth edge, and on the full grid nothing
# cheap knows which side a pixel is on (stop 32, crates/omnimvs-net/README.md): the edges are
# placed on the coarse and half grids, and this selector places them on the half grid. It was
# last trained in cascade-13/14 (stop 27), on the coarse answers of that time; the coarse
# stage has since been trained for about 8,000 more steps (cascade-17 to cascade-25).
# Adam 1e-4 for 6 epochs of 200 steps, then 2 at 1e-5; seed 83. Started in stop 32.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/runs/omnimvs-c28}
RUN=${RUN:-/work/runs/cascade-28}
INIT=${INIT:-/work/main/models/training/cascade-25/epoch4.safetensors}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 --sky-weight 0.1 \
  --convex-upsampling half --stage-intervals 2.5,1.5 \
  --coarse-cue-oversample 2 --coarse-cue-depths 3 --coarse-cue-sgm on \
  --init "$INIT" \
  --train-only upsampling --frozen-norm-stats on --select-by reference \
  --optimizer adam --lr 0.0001 --lr-low 0.00001 --low-lr-epochs 2 --epochs 8 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-val-frames 40 --seed 83 --max-steps 200 \
  --column-window 160 --photometric on --out "$RUN"
