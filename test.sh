#!/usr/bin/env bash
# Installs what is missing, builds, runs every test against a throwaway
# PostgreSQL (the fuzz targets' replay of their seeds among them; the fuzz
# campaign is scripts/fuzz.sh).
# Usage: ./test.sh [ctest options...]   e.g. ./test.sh -L unit
# The `sweep` label — the Monte Carlo tests again at their full size, hours
# in all — is left out unless an argument names it; scripts/sweeps.sh runs it.
set -euo pipefail
root=$(cd "$(dirname "$0")" && pwd)
"$root/scripts/install-deps.sh" --browser
"$root/scripts/build.sh"
ctest_args=()
asks_for_sweep=no
excludes=no
previous=
for a in "$@"; do
  if [[ "$previous" == -LE || "$previous" == --label-exclude ]]; then
    a="$a|^sweep\$"  # ctest keeps one exclusion regex: `sweep` joins the one given
    excludes=yes
  elif [[ "$a" == *sweep* ]]; then
    asks_for_sweep=yes
  fi
  ctest_args+=("$a")
  previous=$a
done
if [[ $asks_for_sweep == no && $excludes == no ]]; then
  ctest_args+=(-LE '^sweep$')
fi
(cd "${INSDIAG_BUILD_DIR:-$root/build}" &&
  "$root/scripts/with-throwaway-pg.sh" ctest --output-on-failure -j "$(nproc)" "${ctest_args[@]}")
