#!/usr/bin/env bash
# pick-7's training (stop 42), the exact command: pick-6 (../pick-6/train-pick-6.sh, /work/data2/pick6.pt)
# widened to read the coarse stage's three most probable modes (PICK_MODES=3: 14 more input
# channels, three more candidates; the new inputs' weights at PyTorch's default init, the new
# candidates' head at zero with biases of -10) and
# trained on the same 1,510 frames with make-data.sh's m-*.npz beside pick-6's f-*.npz, at a one-cycle
# peak of 1e-3 (PICK_LR). Writes pick7.pt / pick7.safetensors every 1,000 steps; resumes from
# pick7.pt.ckpt when started again.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
PICK_NEW_INPUT_SCALE=1 PICK_MODES=3 PICK_INIT=$D/pick6.pt PICK_LR=${PICK_LR:-1e-3} SKY_WEIGHT=0.25 ${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py ${STEPS:-4000} \
  $D/f-things-s201.npz,$D/f-things-s208.npz,$D/f-things-s211.npz,$D/f-house-s202.npz,$D/f-house-s210.npz,$D/f-house-s213.npz,$D/f-things-hard-s203.npz,$D/f-things-hard-s209.npz,$D/f-things-hard-s212.npz,$D/f-house-hard-s207.npz \
  $D/v-things.npz,$D/v-house.npz,$D/v-hhouse.npz 16 ${OUT:-$D/pick7.pt} 2
