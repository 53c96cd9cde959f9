#!/usr/bin/env bash
# Cascade run 6: as run 5 (cascade-4 best, Adam 1e-4, same data and seed) plus a cross-entropy (weight 2)
# between the coarse distribution and a Laplacian around the truth. Resumable: rerun this script.
set -euo pipefail
RUN=/work/runs/cascade-6
if [ -f "$RUN/train_config.json" ]; then
  exec /work/bin/omnimvs-train6 train --resume "$RUN"
fi
exec /work/bin/omnimvs-train6 train --preset cascade --context-pairs 2 --stage-gates on --coarse-distribution 2 \
  --init /work/runs/init/cascade-4-best.safetensors \
  --optimizer adam --lr 0.0001 --lr-low 0.00003 --epochs 30 --low-lr-epochs 10 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --max-steps 100 --max-val-frames 12 --seed 15 \
  --column-window 160 --photometric on --out "$RUN"
