#!/usr/bin/env bash
# Cascade run 8: cascade-7's best (epoch 18, the bundled `cascade`) grown into the photometric
# cue (--zncc-cue on: every stage's volume gets the ZNCC of the cameras' own images at its
# samples, input weights starting at zero), then trained as cascade-7 was: same six sets,
# losses (coarse cross-entropy 2, refinement cross-entropy 1), Adam 1e-4 (3e-5 for the last
# epochs), photometric augmentation, 160-column window, 12 validation frames, seed 15.
# Resumable: rerun this script (it resumes from RUN's latest checkpoint).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-train8}
RUN=${RUN:-/work/runs/cascade-8}
if [ -f "$RUN/train_config.json" ]; then
  exec "$B" train --resume "$RUN"
fi
exec "$B" train --preset cascade --context-pairs 2 --stage-gates on --zncc-cue on \
  --coarse-distribution 2 --refine-distribution 1 \
  --init /work/runs/init/cascade-7-best.safetensors \
  --optimizer adam --lr 0.0001 --lr-low 0.00003 --epochs 30 --low-lr-epochs 8 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 12 --seed 15 \
  --column-window 160 --photometric on --out "$RUN"
