#!/usr/bin/env bash
# Validation-frame sweep of inference-time settings of the cascade's configuration for fixed
# weights: infer on things-s101 and house-s102 frames 481..500 (the trainer's validation frames;
# never the held-out test seeds), scored by omni_np eval-at 160x640 (reference rules).
# Usage: val-variants.sh WEIGHTS(.safetensors, .json beside) "key=value;key=value" ...
#   (keys of the JSON's "cascade" object, values as JSON, e.g. "stage_intervals=[2.5,1.5]")
set -euo pipefail
W=$1; shift
B=${OMNIMVS:-/work/main/target/release/omnimvs}
PY=/work/venv-np/bin/python3; NP=/work/shared/tools/omni_np.py
SETS=${SETS:-things-s101 house-s102}
T=$(mktemp -d)
cp "$W" $T/c.safetensors
for v in "$@"; do
  $PY -c "
import json
c=json.load(open('${W%.safetensors}.json'))
for kv in '$v'.split(';'):
    if kv:
        k,val=kv.split('=',1); c['cascade'][k]=json.loads(val)
json.dump(c,open('$T/c.json','w'),indent=1)"
  for set in $SETS; do
    D=/work/data/$set
    rm -rf $T/out; $B infer $D --frames 481..500 --weights $T/c.safetensors --out $T/out > $T/log 2>&1
    echo "$v $set $($PY $NP eval-at $D $T/out 481 500 160 640)"
  done
done
rm -rf $T
