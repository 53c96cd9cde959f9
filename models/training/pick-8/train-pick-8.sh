#!/usr/bin/env bash
# pick-8's training (stop 42), the exact command: a second pick, run after the bundled pick-6, with
# pick-6's layout, started from pick-6's weights (PICK_INIT) and trained on make-data.sh's s-*.npz
# (pick-6's answers and the inputs for them) at a one-cycle peak of 3e-4 (PICK_LR). SETS names the
# training sets (default: pick-1's 370 frames). Writes OUT (default /work/data2/pick8.pt) and its
# .safetensors every 1,000 steps; resumes from OUT.ckpt when started again. INIT (stop 43) starts
# from other weights than pick-6's (pick-8b: pick-8's, /work/data2/pick8.pt); PREFIX / VPREFIX name
# the training and validation sets' prefix (default s / sv; pick-9: t / tv). WIDTH (stop 44) is the
# U-Net's width (default pick-6's 16; pick-10: 8).
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
SETS=${SETS:-"things-s201 house-s202 things-hard-s203 house-hard-s207"}
TRAIN=$(for s in $SETS; do printf '%s,' $D/${PREFIX:-s}-$s.npz; done)
PICK_INIT=${INIT:-$D/pick6.pt} PICK_LR=${PICK_LR:-3e-4} SKY_WEIGHT=0.25 ${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py ${STEPS:-3000} \
  ${TRAIN%,} $D/${VPREFIX:-sv}-things.npz,$D/${VPREFIX:-sv}-house.npz,$D/${VPREFIX:-sv}-hhouse.npz ${WIDTH:-16} ${OUT:-$D/pick8.pt} 2
