#!/usr/bin/env bash
# Runs cargo with the `libtorch` feature against the PyTorch of scripts/install-libtorch.sh:
#
#   scripts/cargo-libtorch.sh build --release            # -> target/libtorch/release/omnimvs
#   scripts/cargo-libtorch.sh test --release -p omnimvs-net --test parity --test backends
#
# torch-sys finds libtorch through the venv's Python (LIBTORCH_USE_PYTORCH=1); our build script
# (build/libtorch_rpath.rs) writes that torch/lib folder into the binaries' rpath, so they run
# without LD_LIBRARY_PATH. The build goes to its own target folder (target/libtorch) so that it
# does not invalidate the default CPU-only build. Extra cargo features can be added, e.g.
# `--features wgpu`.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="${OMNIMVS_TORCH_VENV:-$root/.venv-torch}"
venv="$(cd "$venv" 2>/dev/null && pwd)" || {
    echo "no PyTorch virtual environment at ${OMNIMVS_TORCH_VENV:-$root/.venv-torch}; run scripts/install-libtorch.sh" >&2
    exit 1
}
command="$1"
shift
export VIRTUAL_ENV="$venv"
export PATH="$venv/bin:$PATH"
export LIBTORCH_USE_PYTORCH=1
# tch 0.22 is written against torch 2.9.0 and refuses other versions unless told; its wrapper
# also compiles against 2.11 (scripts/install-libtorch.sh explains when that is needed).
torch_version="$("$venv/bin/python" -c 'import torch; print(torch.__version__.split("+")[0])')"
if [ "$torch_version" != "2.9.0" ]; then
    echo "building against torch $torch_version (tch's version check bypassed)" >&2
    export LIBTORCH_BYPASS_VERSION_CHECK=1
fi
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target/libtorch}"
cd "$root"
# `-p omnimvs-net` (or `-p omnimvs-train`) selects a library alone; everything else goes through the binary crate.
features=omnimvs-cli/libtorch
for arg in "$@"; do
    case "$arg" in omnimvs-net | omnimvs-train) features=libtorch ;; esac
done
exec cargo "$command" --features "$features" "$@"
