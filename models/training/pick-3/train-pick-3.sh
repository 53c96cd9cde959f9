#!/usr/bin/env bash
# pick-3's training (stop 40), the exact command: pick-2's (../pick-2/train-pick-2.sh: the same
# frames, 4 bands of 64 x 640 a step, Adam one-cycle to 1e-3, width 16, 2 threads, sky in the loss at
# weight 0.25) with the wider layout: eleven candidates (radii 1, 2, 4, 7, 12), depths sampled at
# the 5 x 5 and 25 x 25 extremes, ZNCC channels (make-data.sh's g-*.npz), 10,000 steps. Writes
# pick3.pt / pick3.safetensors every 1,000 steps.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")/../pick-1"
export PICK_RADII=1,2,4,7,12 PICK_DEPTH_RADII=2,12 PICK_ZNCC=5 SKY_WEIGHT=0.25
${TORCH_PY:-/work/venv-torch211/bin/python} train_pick.py ${STEPS:-10000} \
  $D/g-things-s201.npz,$D/g-house-s202.npz,$D/g-things-hard-s203.npz,$D/g-house-hard-s207.npz \
  $D/gv-things.npz,$D/gv-house.npz,$D/gv-hhouse.npz 16 $D/pick3.pt 2
