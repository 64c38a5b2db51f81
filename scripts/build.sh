#!/usr/bin/env bash
# Configures and builds insdiag into build/ (or $INSDIAG_BUILD_DIR).
# Usage: scripts/build.sh [extra cmake -D options...]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir=${INSDIAG_BUILD_DIR:-$root/build}
export CCACHE_BASEDIR=$root
export CCACHE_DIR=${CCACHE_DIR:-$root/.cache/ccache}
werror=OFF
[[ "${CI:-}" == "true" ]] && werror=ON
cmake -S "$root" -B "$build_dir" -G Ninja \
  -DCMAKE_BUILD_TYPE="${INSDIAG_BUILD_TYPE:-Release}" \
  -DINSDIAG_WARNINGS_AS_ERRORS=$werror "$@" >/dev/null
# Two cores and ~1 GB per heavy translation unit: let ninja use them all.
cmake --build "$build_dir" -j "$(nproc)"
