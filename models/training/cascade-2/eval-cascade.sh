#!/usr/bin/env bash
# Held-out evaluation at 160x640, N = 192, scored by the independent omni_np.py: the reference's
# rules (sky not scored) and sky scored as index 0; standard and hard test sets (seeds used
# nowhere else), then the real itbt_sample frames 1-3 by cross-camera photometric difference
# (omni_np.py pred-consistency: lower is better; the second figure is a constant map's).
# Usage: eval-cascade.sh WEIGHTS TAG   (writes into /work/eval)
set -euo pipefail
W=$1; TAG=$2
B=${OMNIMVS:-/work/bin/omnimvs-train}
TINY=${TINY:-}   # e.g. "--weights tiny" once the cascade is the bundled default
PICK=${PICK:-}   # stop 40: a pick's .safetensors to run after WEIGHTS (--pick), else infer's default
PY=/work/venv-np/bin/python3
NP=/work/shared/tools/omni_np.py
mkdir -p /work/eval && cd /work/eval
for set in test-things-s7001 test-house-s7002 test-things-hard-s7003 test-house-hard-s7004; do
  D=/work/data/$set
  [ -f sgm-$set/00020.tiff ] || $B sgm $D --frames 1..20 --out sgm-$set > sgm-$set.log 2>&1
  [ -f tiny-$set/00020.tiff ] || $B infer $D --frames 1..20 $TINY --out tiny-$set > tiny-$set.log 2>&1
  $B infer $D --frames 1..20 --weights $W ${PICK:+--pick $PICK} --out $TAG-$set > $TAG-$set.log 2>&1
  for m in sgm tiny $TAG; do
    echo "$set $m reference $($PY $NP eval-at $D $m-$set 1 20 160 640)"
    echo "$set $m sky $($PY $NP eval-at-sky $D $m-$set 1 20 160 640)"
  done
done
D=/work/shared/data/omnimvs-samples/itbt_sample
[ -f sgm-itbt/00003.tiff ] || $B sgm $D --frames 1..3 --out sgm-itbt > sgm-itbt.log 2>&1
[ -f tiny-itbt/00003.tiff ] || $B infer $D --frames 1..3 $TINY --out tiny-itbt > tiny-itbt.log 2>&1
$B infer $D --frames 1..3 --weights $W ${PICK:+--pick $PICK} --out $TAG-itbt > $TAG-itbt.log 2>&1
for m in sgm tiny $TAG; do
  for f in 1 2 3; do echo "itbt $m frame $f consistency $($PY $NP pred-consistency $D $m-itbt $f)"; done
done
