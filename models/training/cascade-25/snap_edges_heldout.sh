#!/usr/bin/env bash
# Held-out sets with and without --snap-edges (bundled default), reference rules and sky scored.
set -eu
B=/work/main/target/release/omnimvs; PY=/work/venv-np/bin/python3; NP=/work/shared/tools/omni_np.py
cd /work/eval
for set in test-things-s7001 test-house-s7002 test-things-hard-s7003 test-house-hard-s7004; do
  D=/work/data/$set
  $B infer $D --frames 1..20 --snap-edges --out c25snap-$set > c25snap-$set.log 2>&1
  for m in c25e4 c25snap; do
    echo "$set $m reference $($PY $NP eval-at $D $m-$set 1 20 160 640)"
    echo "$set $m sky $($PY $NP eval-at-sky $D $m-$set 1 20 160 640)"
  done
done
D=/work/shared/data/omnimvs-samples/itbt_sample
$B infer $D --frames 1..3 --snap-edges --out c25snap-itbt > c25snap-itbt.log 2>&1
for m in c25e4 c25snap; do
  for f in 1 2 3; do echo "itbt $m frame $f consistency $($PY $NP pred-consistency $D $m-itbt $f)"; done
done
