#!/usr/bin/env bash
# pick-9's training (stop 43), the exact command: a third pick after pick-6 and pick-8b, pick-6's
# layout, started from pick-8b's weights and trained on make-data.sh's t-*.npz (pick-8b's answers and
# the inputs for them) for 2,000 steps at a one-cycle peak of 2e-4, validated on tv-*.npz: pick-8's
# train-pick-8.sh with those sets. Writes /work/data2/pick9.pt and its .safetensors; resumes from
# its .ckpt.
set -euo pipefail
PREFIX=t VPREFIX=tv INIT=${INIT:-/work/data2/pick8b.pt} PICK_LR=${PICK_LR:-2e-4} STEPS=${STEPS:-2000} \
  OUT=${OUT:-/work/data2/pick9.pt} exec "$(dirname "$0")/../pick-8/train-pick-8.sh"
