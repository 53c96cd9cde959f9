#!/usr/bin/env bash
# pick-6's extra data (stop 41): fresh frames of three more seeds no run had used (211: 300 things frames,
# 212: 120 hard things frames, 213: 150 house frames), the bundled cascade's answers on them without its pick
# (`infer --pick off`: the pick reads the network's own answers), and pick-2's inputs
# (../pick-1/pick_inputs.py, pick-1/2's layout) as f-*.npz beside pick-1's under /work/data2.
# Resumable: a step whose output exists is skipped.
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-40b}
P=${PY:-/work/venv-np/bin/python3}
S=$(cd "$(dirname "$0")/../pick-1" && pwd)/pick_inputs.py
D=/work/data2
mkdir -p $D && cd $D
for s in things:things-s211:300:211: things:things-hard-s212:120:212:hard house:house-s213:150:213:; do
  IFS=: read -r kind d n seed diff <<< "$s"
  [ -f $d/done ] || { $B synth --kind $kind ${diff:+--difficulty $diff} --frames 1..$n --out $d --seed $seed \
    > $d.synth.log 2>&1 && touch $d/done; }
  [ -f out-$d/done ] || { $B infer --pick off --frames 1..$n --out out-$d $d > out-$d.log 2>&1 && touch out-$d/done; }
  [ -f f-$d.npz ] || $P $S $d out-$d 1 $n f-$d.npz
done
echo DATA-DONE
