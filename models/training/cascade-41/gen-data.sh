#!/usr/bin/env bash
# Stop 36's data on a fresh machine (/work/data was gone): validation and test frames first, then
# the first frames of the five training sets of cascade-40's mix (synth is deterministic per seed
# and frame, so these are the same frames the earlier runs saw). Resumable: synth skips frames
# already written. Usage: gen-data.sh [BINARY] [TRAIN_FRAMES]
set -euo pipefail
B=${1:-/work/bin/omnimvs}
N=${2:-100}
R=/work/shared/data/omnimvs-samples/itbt_sample/config.yaml
mkdir -p /work/data && cd /work/data
$B synth --kind things --frames 481..500 --out things-s101 --seed 101
$B synth --kind house  --frames 481..500 --out house-s102  --seed 102
$B synth --kind things --frames 1..20 --out test-things-s7001 --seed 7001
$B synth --kind house  --frames 1..20 --out test-house-s7002  --seed 7002
$B synth --kind things --difficulty hard --frames 1..20 --out test-things-hard-s7003 --seed 7003
$B synth --kind house  --difficulty hard --frames 1..20 --out test-house-hard-s7004  --seed 7004
$B synth --kind things --frames 1..$N   --out things-s101 --seed 101
$B synth --kind house  --frames 1..$N   --out house-s102  --seed 102
$B synth --kind things --difficulty hard --frames 1..$N --out things-hard-s103 --seed 103
$B synth --kind house  --difficulty hard --rig $R --size 766x800 --frames 1..$N --out house-hard-itbtrig-s105 --seed 105
$B synth --kind things --difficulty hard --rig $R --size 766x800 --frames 1..$N --out things-hard-itbtrig-s106 --seed 106
echo GEN-DATA-DONE
