#!/usr/bin/env bash
# One training run of `omnimvs train` from a recipe's argument file, resumable.
#
#   scripts/train/run.sh ARGS_FILE RUN_DIR
#
# ARGS_FILE holds the run's options for `omnimvs train` on one line (the `*.args` files under
# models/recipes/), with two placeholders:
#   $DATA  the folder that holds the generated datasets (scripts/train/make-data.sh writes them)
#   $INIT  the weights the run starts from (the previous step's chosen epoch)
# Environment:
#   DATA     required when the arguments name $DATA
#   INIT     required when the arguments name $INIT
#   OMNIMVS  the binary (default: `omnimvs` on PATH, else target/release/omnimvs)
#   EXTRA    more options appended to the command (e.g. "--backend libtorch")
# When RUN_DIR already holds a run (its train_config.json), the run is resumed from its latest
# checkpoint instead: start the script again after an interruption.
set -euo pipefail
if [ $# -ne 2 ]; then
  sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
args_file=$1
run=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OMNIMVS:-$(command -v omnimvs || echo "$root/target/release/omnimvs")}
if [ ! -x "$bin" ]; then
  echo "error: no omnimvs binary at '$bin' (build it with 'cargo build --release' or set OMNIMVS)" >&2
  exit 1
fi
if [ -f "$run/train_config.json" ]; then
  echo "resuming $run" >&2
  # shellcheck disable=SC2086
  exec "$bin" train --resume "$run" ${EXTRA:-}
fi
if [ ! -f "$args_file" ]; then
  echo "error: argument file '$args_file' not found" >&2
  exit 1
fi
line=$(grep -v '^#' "$args_file" | tr '\n' ' ')
for var in DATA INIT; do
  if [[ $line == *"\$$var"* ]]; then
    if [ -z "${!var:-}" ]; then
      echo "error: $args_file uses \$$var: set $var=..." >&2
      exit 1
    fi
    line=${line//\$$var/${!var}}
  fi
done
# shellcheck disable=SC2086
read -r -a argv <<< "$line"
echo "$bin train ${argv[*]} --out $run ${EXTRA:-}" >&2
# shellcheck disable=SC2086
exec "$bin" train "${argv[@]}" --out "$run" ${EXTRA:-}
