#!/usr/bin/env bash
# Cascade training run 1 (resumable: rerun this script; it resumes when the run exists).
# Epochs 1-2 trained on whole panoramas with per-camera feature batches; from epoch 3 the
# cameras go through the features as one batch and the refinement stages train on a
# 160-column window of longitude (--column-window 160, recorded in train_config.json).
set -euo pipefail
RUN=/work/runs/cascade-1
if [ -f "$RUN/train_config.json" ]; then
  exec /work/bin/omnimvs-train train --resume "$RUN" --column-window 160
fi
exec /work/bin/omnimvs-train train --preset cascade --optimizer adam --lr 0.001 --lr-low 0.0001 \
  --data /work/data/things-s101,/work/data/house-s102 --val-frames 481..500 \
  --epochs 200 --max-steps 100 --max-val-frames 6 --seed 11 --column-window 160 --out "$RUN"
