#!/usr/bin/env bash
# Held-out evaluation at 160x640, N = 192, scored by omni_np.py (reference rules, and sky scored).
# Usage: eval-cascade.sh WEIGHTS TAG
set -euo pipefail
W=$1; TAG=$2
B=/work/bin/omnimvs-train
PY=/work/venv-np/bin/python3
NP=/work/shared/tools/omni_np.py
cd /work/eval
for set in test-things-s7001 test-house-s7002; do
  D=/work/data/$set
  [ -f sgm-$set/00020.tiff ] || $B sgm $D --frames 1..20 --out sgm-$set > sgm-$set.log 2>&1
  [ -f tiny-$set/00020.tiff ] || $B infer $D --frames 1..20 --out tiny-$set > tiny-$set.log 2>&1
  $B infer $D --frames 1..20 --weights $W --out $TAG-$set > $TAG-$set.log 2>&1
  for m in sgm tiny $TAG; do
    echo "$set $m reference $($PY $NP eval-at $D $m-$set 1 20 160 640)"
    echo "$set $m sky $($PY $NP eval-at-sky $D $m-$set 1 20 160 640)"
  done
done
