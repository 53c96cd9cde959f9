#!/usr/bin/env bash
# Training and test data for cascade-8, regenerated on a fresh machine (the earlier sessions'
# /work/data was gone): the same generators, seeds and frames as cascade-7's sets (synth is
# deterministic per seed and frame), fewer training frames (about 1,300 instead of 2,260: this
# run's few thousand steps see each a couple of times, under 8 rig rotations and photometric
# augmentation). Test seeds 7001-7004 are used nowhere else.
# Resumable: synth skips frames already written. Usage: gen-data.sh [BINARY]
set -euo pipefail
B=${1:-/work/bin/omnimvs}
R=/work/shared/data/omnimvs-samples/itbt_sample/config.yaml
mkdir -p /work/data && cd /work/data
$B synth --kind things --frames 1..20 --out test-things-s7001 --seed 7001
$B synth --kind house  --frames 1..20 --out test-house-s7002  --seed 7002
$B synth --kind things --difficulty hard --frames 1..20 --out test-things-hard-s7003 --seed 7003
$B synth --kind house  --difficulty hard --frames 1..20 --out test-house-hard-s7004  --seed 7004
$B synth --kind things --frames 481..500 --out things-s101 --seed 101
$B synth --kind house  --frames 481..500 --out house-s102  --seed 102
$B synth --kind things --frames 1..300   --out things-s101 --seed 101
$B synth --kind house  --frames 1..300   --out house-s102  --seed 102
$B synth --kind things --difficulty hard --frames 1..250 --out things-hard-s103 --seed 103
$B synth --kind house  --difficulty hard --frames 1..150 --out house-hard-s104  --seed 104
$B synth --kind house  --difficulty hard --rig $R --size 766x800 --frames 1..150 --out house-hard-itbtrig-s105 --seed 105
$B synth --kind things --difficulty hard --rig $R --size 766x800 --frames 1..150 --out things-hard-itbtrig-s106 --seed 106
echo GEN-DATA-DONE
