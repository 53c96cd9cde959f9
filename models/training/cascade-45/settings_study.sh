#!/usr/bin/env bash
# settings_study.sh WEIGHTS_BASE TAG HALF FULL [FIRST LAST] (stop 37): a trained cascade's settings that no weight
# depends on, changed in a copy of its JSON: stage_intervals HALF,FULL and any KEY=JSON of SET (e.g.
# SET="coarse_cue_depths=5"); infers validation frames FIRST..LAST of things-s101 and house-s102 and scores
# them at 160x640 (omni_np eval-at, reference rules). Writes under ${EXP:-/work/exp}.
set -euo pipefail
W=$1; TAG=$2; H=$3; F=$4; A=${5:-481}; B=${6:-500}
EXP=${EXP:-/work/exp}
D=$EXP/w-$TAG; mkdir -p $D
cp $W.safetensors $D/w.safetensors
python3 - "$W.json" "$D/w.json" "$H" "$F" <<'PY'
import json,sys
c=json.load(open(sys.argv[1])); c["cascade"]["stage_intervals"]=[float(sys.argv[3]),float(sys.argv[4])]
import os
for kv in os.environ.get("SET","").split():
  k,v=kv.split("="); c["cascade"][k]=json.loads(v)
json.dump(c,open(sys.argv[2],"w"),indent=1)
PY
for s in things-s101 house-s102; do
  O=$EXP/out-$TAG-$s; rm -rf $O
  ${OMNIMVS:-/work/bin/omnimvs} infer --weights $D/w.safetensors --frames $A..$B --out $O /work/data/$s > $O.log 2>&1
  echo "$TAG $s $(/work/venv-np/bin/python3 /work/shared/tools/omni_np.py eval-at /work/data/$s $O $A $B 160 640 2>&1 | tail -1)"
done
