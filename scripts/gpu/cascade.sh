#!/usr/bin/env bash
# The bundled cascade on a GPU machine in one call (for GPU time that comes in short slots): parity of the
# whole inference against the CPU, the benchmark per stage with its training step, the paper
# preset's training step against PyTorch's on the same GPU, and a fine-tuning run of the bundled
# cascade trained there end to end. Build the binaries here first (README, "GPU procedure");
# the GPU machine needs only the driver and PyTorch. Every step has its own time limit, so that
# one that hangs cannot eat the others' time; the run's results end up in $OUT.
#
#   scripts/gpu/cascade.sh            # on the GPU machine, from the repository's root
#
# Environment (defaults in brackets):
#   OUT             results folder [./gpu-results]: results.tar.gz (every step's log and JSON, the
#                   evaluations, the training run's weights, metrics and curves)
#   OMNIMVS_TORCH   omnimvs built with --features libtorch against the machine's PyTorch version
#                   [./dist/omnimvs-libtorch]
#   OMNIMVS_WGPU    omnimvs built with --features wgpu [./dist/omnimvs-wgpu]; skipped if missing
#   BACKEND         the GPU backend of the libtorch binary [libtorch-cuda:0]
#   TRAIN_FRAMES    training frames generated per set [40]; TRAIN_SECONDS: the training run's
#                   limit [180]; TRAIN_LR [0.00001]; TRAIN_LR_LOW: the rate of the last
#                   --low-lr-epochs [TRAIN_LR / 10]; TRAIN_WINDOW: --column-window [none: the
#                   whole panorama]; TRAIN_INIT: the weights it starts from [the bundled
#                   cascade]; TRAIN_EXTRA: more options of `omnimvs train`, space-separated
#                   (e.g. "--train-only coarse --coarse-feature-channels 32")
#   TRAIN_B_EXTRA   when set, a second training run beside the first on the same GPU and data
#                   (an A/B in one call), with these options after TRAIN_EXTRA's; its results
#                   under run-b/ (each run gets half of LOADER_THREADS)
#   TRAIN_A_EXTRA   options of the first run alone, after TRAIN_EXTRA's (an option that the two
#                   runs set differently goes here and in TRAIN_B_EXTRA: a repeated one is refused)
#   STEPS_PER_EPOCH [100]; TRAIN_EPOCHS: epochs of the run, the last 3 at TRAIN_LR_LOW [100]
#   VAL_FRAMES      validation frames of the two standard sets [481..488]
#   LOADER_THREADS  threads preparing the training samples [8] (one left the GPU idle two
#                   thirds of the time)
#   WORK            scratch folder for data and runs [/tmp/omnimvs-gpu]
#   ITBT            the itbt_sample config.yaml, for the training sets on its rig [none: skipped]
#   PYTHON          [python3]
#   DEADLINE        seconds from the start after which no step starts, and to which the last
#                   one's limit is cut [540]
#   SKIP            space-separated steps to skip: parity bench paper train wgpu
set -uo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="${OUT:-$PWD/gpu-results}"
bin="${OMNIMVS_TORCH:-$PWD/dist/omnimvs-libtorch}"
wbin="${OMNIMVS_WGPU:-$PWD/dist/omnimvs-wgpu}"
backend="${BACKEND:-libtorch-cuda:0}"
python="${PYTHON:-python3}"
work="${WORK:-/tmp/omnimvs-gpu}"
frames="${TRAIN_FRAMES:-40}"
skip=" ${SKIP:-} "
val="${VAL_FRAMES:-481..488}"
deadline="${DEADLINE:-540}"
logs="$work/logs"
mkdir -p "$out" "$work" "$logs"
export OMNIMVS_CACHE_DIR="$work/cache"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$work/xdg}"
mkdir -p "$XDG_RUNTIME_DIR"
torch_lib="$("$python" -c 'import os, torch; print(os.path.join(os.path.dirname(torch.__file__), "lib"))' 2>/dev/null || true)"
export LD_LIBRARY_PATH="$torch_lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
t0=$(date +%s)
stamp() { echo "[$(($(date +%s) - t0)) s] $*"; }
want() { [[ "$skip" != *" $1 "* ]]; }
# Packs everything so far into $OUT/results.tar.gz (after every step: a call cut short still
# returns what it measured).
pack() {
    (
        cd "$work" || exit 0
        local files=(logs)
        for f in eval-gpu eval-cpu; do
            [ -e "$f" ] && files+=("$f")
        done
        for r in run run-b; do
            for f in metrics.jsonl train_config.json best.safetensors best.json model.safetensors \
                model.json curves.png start.json; do
                [ -e "$r/$f" ] && files+=("$r/$f")
            done
        done
        # Two runs may pack at once: each through its own temporary file.
        local tmp="$out/results.tar.gz.$BASHPID"
        tar czf "$tmp" "${files[@]}" && mv "$tmp" "$out/results.tar.gz"
    )
}
# Runs a command under a time limit, its output to the console and $work/logs/NAME.log, with the
# GPU's used memory sampled every 100 ms (whole device, CUDA context included).
step() {
    local name="$1" limit="$2"
    shift 2
    local left=$((deadline - ($(date +%s) - t0)))
    if [ "$left" -lt 20 ]; then
        stamp "== $name skipped: ${left} s left of the ${deadline} s deadline"
        return 0
    fi
    [ "$limit" -gt "$left" ] && limit=$left
    stamp "== $name (limit ${limit} s): $*"
    local sampler=""
    if command -v nvidia-smi >/dev/null; then
        nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 100 \
            >"$logs/$name-gpu-memory.csv" 2>/dev/null &
        sampler=$!
    fi
    local start status=0
    start=$(date +%s.%N)
    timeout "$limit" "$@" >"$logs/$name.log" 2>&1 || status=$?
    local wall
    wall=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
    if [ -n "$sampler" ]; then
        kill "$sampler" 2>/dev/null
        wait "$sampler" 2>/dev/null
        echo "peak GPU memory used: $(sort -n "$logs/$name-gpu-memory.csv" | tail -1) MiB" >>"$logs/$name.log"
        rm -f "$logs/$name-gpu-memory.csv"
    fi
    echo "exit $status, wall ${wall} s" >>"$logs/$name.log"
    tail -n 25 "$logs/$name.log"
    pack
    return 0
}

# Compares the index maps of frames 1-2 in two `infer` outputs (step NAME): largest and mean
# difference, and the share of pixels that differ by more than 0.5 and 0.01 index.
compare_maps() {
    step "$1" 60 "$python" - "$2" "$3" <<'PY'
import sys, numpy as np, tifffile
a_dir, b_dir = sys.argv[1], sys.argv[2]
for f in (1, 2):
    a = tifffile.imread(f"{a_dir}/{f:05d}_index.tiff").astype(np.float64)
    b = tifffile.imread(f"{b_dir}/{f:05d}_index.tiff").astype(np.float64)
    d = np.abs(a - b)
    print(f"frame {f}: shape {a.shape}, index max diff {d.max():.3e}, mean {d.mean():.3e}, "
          f"pixels > 0.5: {(d > 0.5).mean() * 100:.4f} %, > 0.01: {(d > 0.01).mean() * 100:.4f} %")
PY
}

stamp "env"
{
    date -u
    nvidia-smi
    "$python" -c 'import torch; print("torch", torch.__version__, "CUDA", torch.version.cuda, "available", torch.cuda.is_available())'
    nproc
    "$bin" --version
} >"$logs/env.log" 2>&1
cat "$logs/env.log"

# The frames: held-out test frames for parity (the same seed and frames as the README's tables,
# synth is deterministic), and the bundled cascade's training sets (scripts/train/make-data.sh's seeds,
# the first TRAIN_FRAMES frames of each, validation frames 481..488 of the two standard sets),
# generated in the background while the GPU measurements run.
# ITBT: the itbt_sample config.yaml, for the training sets on its rig (skipped without it).
rig="${ITBT:-}"
D=$work/data
step synth-test 120 "$bin" synth --kind things --frames 1..2 --out "$D/test-things-s7001" --seed 7001
if want train; then
    (
        nice -n 5 "$bin" synth --kind things --frames "$val" --out "$D/things-s101" --seed 101
        nice -n 5 "$bin" synth --kind house --frames "$val" --out "$D/house-s102" --seed 102
        nice -n 5 "$bin" synth --kind things --frames 1..$frames --out "$D/things-s101" --seed 101
        nice -n 5 "$bin" synth --kind house --frames 1..$frames --out "$D/house-s102" --seed 102
        nice -n 5 "$bin" synth --kind things --difficulty hard --frames 1..$frames --out "$D/things-hard-s103" --seed 103
        nice -n 5 "$bin" synth --kind house --difficulty hard --frames 1..$frames --out "$D/house-hard-s104" --seed 104
        if [ -n "$rig" ]; then
            nice -n 5 "$bin" synth --kind house --difficulty hard --rig "$rig" --size 766x800 --frames 1..$frames --out "$D/house-hard-itbtrig-s105" --seed 105
            nice -n 5 "$bin" synth --kind things --difficulty hard --rig "$rig" --size 766x800 --frames 1..$frames --out "$D/things-hard-itbtrig-s106" --seed 106
        fi
    ) >"$logs/synth-train.log" 2>&1 &
    synth_pid=$!
fi

if want parity; then
    T=$D/test-things-s7001
    step infer-cpu 120 "$bin" infer "$T" --frames 1..2 --backend cpu --out "$work/infer-cpu"
    step infer-gpu 120 "$bin" infer "$T" --frames 1..2 --backend "$backend" --out "$work/infer-gpu"
    compare_maps parity-compare "$work/infer-cpu" "$work/infer-gpu"
    step eval-gpu 180 "$bin" eval --data "$T" --frames 1..2 --method net --backend "$backend" --out "$work/eval-gpu"
    step eval-cpu 180 "$bin" eval --data "$T" --frames 1..2 --method net --backend cpu --out "$work/eval-cpu"
fi

if want bench; then
    step bench-cascade-gpu 150 "$bin" bench --config "$root/models/omnimvs-cascade.json" \
        --backend "$backend" --repeats 5 --train-steps 5 --json "$logs/bench-cascade-gpu.json"
fi


if want train; then
    stamp "waiting for the training data"
    wait "$synth_pid"
    tail -n 3 "$logs/synth-train.log"
    sets=$(ls -d "$D"/*-s1?? | paste -sd, -)
    window=()
    [ -n "${TRAIN_WINDOW:-}" ] && window=(--column-window "$TRAIN_WINDOW")
    lr="${TRAIN_LR:-0.00001}"
    lr_low="${TRAIN_LR_LOW:-$(awk -v r="$lr" 'BEGIN { print r / 10 }')}"
    read -r -a extra <<<"${TRAIN_EXTRA:-}"
    threads="${LOADER_THREADS:-8}"
    [ -n "${TRAIN_B_EXTRA:-}" ] && threads=$(((threads + 1) / 2))
    # One training run (step NAME, folder RUN, more options after TRAIN_EXTRA's).
    train_run() {
        local name="$1" run="$2"
        shift 2
        step "$name" "${TRAIN_SECONDS:-180}" "$bin" train --preset cascade --context-pairs 2 \
            --stage-gates on --zncc-cue on --coarse-distribution 2 --refine-distribution 1 \
            --sky-weight 0.1 --convex-upsampling half \
            --init "${TRAIN_INIT:-$root/models/omnimvs-cascade.safetensors}" \
            --frozen-norm-stats on --select-by reference --optimizer adam --lr "$lr" \
            --lr-low "$lr_low" --low-lr-epochs 3 \
            --epochs "${TRAIN_EPOCHS:-100}" --max-steps "${STEPS_PER_EPOCH:-100}" --data "$sets" \
            --val-frames "$val" --max-val-frames 16 --loader-threads "$threads" "${extra[@]}" \
            "$@" --seed 29 --photometric on "${window[@]}" --backend "$backend" --out "$run"
    }
    b_pid=""
    if [ -n "${TRAIN_B_EXTRA:-}" ]; then
        read -r -a extra_b <<<"$TRAIN_B_EXTRA"
        train_run train-cascade-b "$work/run-b" "${extra_b[@]}" &
        b_pid=$!
    fi
    read -r -a extra_a <<<"${TRAIN_A_EXTRA:-}"
    train_run train-cascade "$work/run" "${extra_a[@]}"
    [ -n "$b_pid" ] && wait "$b_pid"
    for r in run run-b; do
        [ -e "$work/$r/metrics.jsonl" ] && { echo "== $r"; tail -n 20 "$work/$r/metrics.jsonl"; }
    done
    pack
fi

if want paper; then
    step bench-paper-gpu 100 "$bin" bench --preset paper --backend "$backend" --repeats 3 \
        --train-steps 3 --json "$logs/bench-paper-gpu.json"
    step bench-paper-pytorch 80 "$python" "$root/scripts/net_parity/bench_torch.py" paper 3 \
        --device cuda --train-steps 3
fi

if want wgpu && [ -x "$wbin" ]; then
    T=$D/test-things-s7001
    step infer-wgpu 80 "$wbin" infer "$T" --frames 1..2 --backend wgpu --out "$work/infer-wgpu"
    compare_maps parity-compare-wgpu "$work/infer-cpu" "$work/infer-wgpu"
    step bench-cascade-wgpu 80 "$wbin" bench --config "$root/models/omnimvs-cascade.json" \
        --backend wgpu --repeats 3 --train-steps 3 --json "$logs/bench-cascade-wgpu.json"
fi

pack
ls -la "$out"
stamp "done"
