#!/usr/bin/env bash
# Training data on the real itbt_sample rig's geometry (0.3 m baselines, minimum depth 0.5 m),
# hard difficulty, images at half the rig's size (766x800), for the next fine-tuning stage.
set -euo pipefail
B=/work/bin/omnimvs
R=/work/shared/data/omnimvs-samples/itbt_sample/config.yaml
cd /work/data
$B synth --kind house  --difficulty hard --rig $R --size 766x800 --frames 1..200 --out house-hard-itbtrig-s105 --seed 105 &
$B synth --kind things --difficulty hard --rig $R --size 766x800 --frames 1..200 --out things-hard-itbtrig-s106 --seed 106
wait
echo GEN-ITBT-DONE
