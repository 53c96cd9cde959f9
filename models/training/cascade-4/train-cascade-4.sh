#!/usr/bin/env bash
# Cascade run 4: cascade-3's best (epoch 4) grown by two context pairs at stride 8 and gated
# refinement stages (they start as the identity / at 0.98), trained on the same six sets with
# photometric augmentation; 12 validation frames. Resumable: rerun this script.
set -euo pipefail
RUN=/work/runs/cascade-4
if [ -f "$RUN/train_config.json" ]; then
  exec /work/bin/omnimvs-train4 train --resume "$RUN"
fi
exec /work/bin/omnimvs-train4 train --preset cascade --context-pairs 2 --stage-gates on \
  --init /work/runs/init/cascade-3-best.safetensors \
  --optimizer adam --lr 0.0003 --lr-low 0.0001 \
  --data /work/data/things-s101,/work/data/house-s102,/work/data/things-hard-s103,/work/data/house-hard-s104,/work/data/house-hard-itbtrig-s105,/work/data/things-hard-itbtrig-s106 \
  --val-frames 481..500 --epochs 100 --max-steps 100 --max-val-frames 12 --seed 14 \
  --column-window 160 --photometric on --out "$RUN"
