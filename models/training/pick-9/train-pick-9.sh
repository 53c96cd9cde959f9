#!/usr/bin/env bash
# pick-9's training (stop 43): a third pick after pick-6 and pick-8b, pick-6's layout, started from
# pick-8b's weights and trained on make-data.sh's t-*.npz (pick-8b's answers and the inputs for
# them), validated on tv-*.npz. Writes OUT (default /work/data2/pick9.pt) and its .safetensors every
# 1,000 steps; resumes from OUT.ckpt.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
SETS=${SETS:-"things-s201 house-s202 things-hard-s203 house-hard-s207"}
TRAIN=$(for s in $SETS; do printf '%s,' $D/t-$s.npz; done)
PICK_INIT=${INIT:-$D/pick8b.pt} PICK_LR=${PICK_LR:-2e-4} SKY_WEIGHT=0.25 ${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py ${STEPS:-2000} \
  ${TRAIN%,} $D/tv-things.npz,$D/tv-house.npz,$D/tv-hhouse.npz 16 ${OUT:-$D/pick9.pt} 2
