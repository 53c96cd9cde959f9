#!/usr/bin/env bash
# pick-5's extra data (stop 41): fresh frames of three seeds no run had used (208: 300 things frames,
# 209: 120 hard things frames, 210: 150 house frames), the bundled cascade's answers on them without its pick
# (`infer --pick off`: the pick reads the network's own answers), and pick-2's inputs
# (../pick-1/pick_inputs.py, pick-1/2's layout) as f-*.npz beside pick-1's under /work/data2.
# Resumable: a step whose output exists is skipped. SETS (kind:folder:frames:seed:difficulty, space
# separated) replaces the three sets (../pick-6/make-data.sh).
set -euo pipefail
B=${OMNIMVS:-/work/bin/omnimvs-40b}
P=${PY:-/work/venv-np/bin/python3}
S=$(cd "$(dirname "$0")/../pick-1" && pwd)/pick_inputs.py
D=/work/data2
mkdir -p $D && cd $D
SETS=${SETS:-"things:things-s208:300:208: things:things-hard-s209:120:209:hard house:house-s210:150:210:"}
for s in $SETS; do
  IFS=: read -r kind d n seed diff <<< "$s"
  [ -f $d/done ] || { $B synth --kind $kind ${diff:+--difficulty $diff} --frames 1..$n --out $d --seed $seed \
    > $d.synth.log 2>&1 && touch $d/done; }
  [ -f out-$d/done ] || { $B infer --pick off --frames 1..$n --out out-$d $d > out-$d.log 2>&1 && touch out-$d/done; }
  [ -f f-$d.npz ] || $P $S $d out-$d 1 $n f-$d.npz
done
echo DATA-DONE
