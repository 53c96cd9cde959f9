#!/usr/bin/env bash
# Whole-process time of `omnimvs infer --weights cascade` against `omnimvs sgm` on the same
# frames, run alternately in the same session (issue #11: the cascade at most twice SGM's time).
#
#   scripts/speed/cascade_vs_sgm.sh [OMNIMVS_BIN] [DATASET] [FRAMES] [ROUNDS]
#
# Defaults: target/release/omnimvs, ../data/test-things-s7001 (made by `omnimvs synth`), 1..4,
# 5 rounds after one unmeasured warm-up round; WEIGHTS=FILE times other cascade weights than
# the bundled `cascade`; PICK=off leaves out the learnt pick after the bundled cascade (`infer
# --pick`, stop 39; binaries before it have no such option). Prints wall, user and system seconds and peak
# resident memory of every run, then the medians and the ratio of the medians.
set -euo pipefail
BIN=${1:-target/release/omnimvs}
DATA=${2:-../data/test-things-s7001}
FRAMES=${3:-1..4}
ROUNDS=${4:-5}
WEIGHTS=${WEIGHTS:-cascade}
PICK=${PICK:-auto}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (GNU time)" >&2; exit 1; }
run() { # METHOD -> "wall user sys peak_kb"
  local args=(sgm "$DATA" --frames "$FRAMES" --out "$OUT/$1")
  [ "$1" = cascade ] && args=(infer "$DATA" --frames "$FRAMES" --weights "$WEIGHTS" --pick "$PICK" --out "$OUT/$1")
  rm -rf "${OUT:?}/$1"
  /usr/bin/time -f "%e %U %S %M" -o "$OUT/time" "$BIN" "${args[@]}" >/dev/null 2>"$OUT/err" ||
    { cat "$OUT/err" >&2; exit 1; }
  cat "$OUT/time"
}
: >"$OUT/cascade.txt"; : >"$OUT/sgm.txt"
for r in $(seq 0 "$ROUNDS"); do
  for m in cascade sgm; do
    line=$(run $m)
    if [ "$r" -gt 0 ]; then
      echo "$line" >>"$OUT/$m.txt"
      echo "round $r $m: wall ${line%% *} s (user, system, peak KB: ${line#* })"
    fi
  done
done
median() { sort -n | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
c=$(cut -d' ' -f1 "$OUT/cascade.txt" | median)
s=$(cut -d' ' -f1 "$OUT/sgm.txt" | median)
cp=$(cut -d' ' -f4 "$OUT/cascade.txt" | sort -n | tail -1)
sp=$(cut -d' ' -f4 "$OUT/sgm.txt" | sort -n | tail -1)
echo "median wall: cascade $c s, sgm $s s, ratio $(awk -v c="$c" -v s="$s" 'BEGIN {printf "%.3f", c / s}')"
echo "peak memory: cascade $((cp / 1024)) MB, sgm $((sp / 1024)) MB"
