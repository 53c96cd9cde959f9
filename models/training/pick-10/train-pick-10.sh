#!/usr/bin/env bash
# pick-10's training (stop 44), the exact commands: a half-width second pick (U-Net width 8 instead of
# 16, a quarter of the multiplications) for `--pick chain`, trained on pick-6's answers on all 1,510
# frames (pick-8b's data, s-*.npz) with pick-8's script.
#  1. `l1`: from pick-8b's weights cut to width 8 (prune.py), by the L1 alone on a 6,000-step
#     schedule, stopped by hand after its step-4,000 weights were written (see README.md), which
#     were then copied: `cp /work/data2/pick10-l1.pt /work/data2/pick10-l1-s4000.pt` (the run
#     itself wrote them as pick10.pt; the name here keeps them apart from step 2's).
#  2. `distil`: from there, pick-8b distilled into it (PICK_TEACHER: the KL divergence of its
#     candidate weights from pick-8b's, weight 10, besides the L1), 4,000 steps;
#     /work/data2/pick10.pt and .safetensors.
# Each writes its weights every 1,000 steps and resumes from its .ckpt when started again.
set -euo pipefail
D=/work/data2
cd "$(dirname "$0")"
SETS="things-s201 house-s202 things-hard-s203 house-hard-s207 things-s208 things-s211 house-s210 house-s213 things-hard-s209 things-hard-s212"
export SETS WIDTH=8
case "${1:-distil}" in
  l1)
    [ -f $D/pick10-init.pt ] || ${TORCH_PY:-/work/venv-torch211/bin/python} prune.py $D/pick8b.pt $D/pick10-init.pt
    INIT=$D/pick10-init.pt PICK_LR=6e-4 STEPS=6000 OUT=$D/pick10-l1.pt ../pick-8/train-pick-8.sh ;;
  distil)
    PICK_TEACHER=$D/pick8b.pt PICK_DISTILL=10 INIT=$D/pick10-l1-s4000.pt PICK_LR=6e-4 STEPS=4000 \
      OUT=$D/pick10.pt ../pick-8/train-pick-8.sh ;;
esac
