#!/usr/bin/env bash
# Installs what is missing, builds, runs every test against a throwaway
# PostgreSQL, then the fuzzers' short run.
# Usage: ./test.sh [ctest options...]   e.g. ./test.sh -L unit
set -euo pipefail
root=$(cd "$(dirname "$0")" && pwd)
"$root/scripts/install-deps.sh" --browser
"$root/scripts/build.sh"
(cd "${INSDIAG_BUILD_DIR:-$root/build}" &&
  "$root/scripts/with-throwaway-pg.sh" ctest --output-on-failure -j "$(nproc)" "$@")
# The fuzzers' short run: every regression input, then 10 s of each
# (docs/RELIABILITY.md; the campaign is scripts/fuzz.sh with a longer time).
# Skipped when ctest was asked for a subset.
if (($# == 0)); then
  "$root/scripts/fuzz.sh" 10
fi
