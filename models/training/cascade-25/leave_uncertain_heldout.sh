#!/usr/bin/env bash
# Held-out figures of `infer --max-entropy` / `--max-spread` (the bundled default) and of
# `sgm --min-confidence`, at 160x640, N = 192, reference rules (omni_np eval-at: the pixels left
# without an answer are not scored) with each output's coverage as `omnimvs` reports it.
# Output: leave_uncertain_heldout.txt. Usage: leave_uncertain_heldout.sh   (writes into /work/eval)
set -euo pipefail
B=${OMNIMVS:-/work/main/target/release/omnimvs}
PY=/work/venv-np/bin/python3; NP=/work/shared/tools/omni_np.py
cd /work/eval
score() { # SET DIR LOG LABEL
  echo "$1 $4 reference $($PY $NP eval-at /work/data/$1 $2 1 20 160 640) $(grep -o 'coverage [0-9.]* %' $3 | head -1)"
}
for set in test-things-s7001 test-house-s7002; do
  $B infer /work/data/$set --frames 1..20 --max-entropy 2.6 --out c25me-$set > c25me-$set.log 2>&1
  score $set c25me-$set c25me-$set.log "max-entropy 2.6"
done
for set in test-things-s7001 test-house-s7002; do
  $B infer /work/data/$set --frames 1..20 --max-spread 30 --out c25ms-$set > c25ms-$set.log 2>&1
  score $set c25ms-$set c25ms-$set.log "max-spread 30"
done
for c in 0.02 0.05 0.12 0.2; do
  $B sgm /work/data/test-things-s7001 --frames 1..20 --min-confidence $c --out sgmc$c > sgmc$c.log 2>&1
  score test-things-s7001 sgmc$c sgmc$c.log "sgm --min-confidence $c"
done
