#!/usr/bin/env bash
# The Monte Carlo tests at their full size: the ctest label `sweep`, the
# same test bodies as the suite's with INSDIAG_SWEEP=full (more seeds, every
# scenario; tests/support/monte_carlo.h). Builds first, then runs each sweep
# test on its own, its whole output in build/sweeps/NAME.log, and prints
# each test's time and result and the counts and rates it printed (the
# lines holding "(at least N)" or "(at most N)"), the figures the docs quote.
# Hours on two cores. ./test.sh and CI leave this label out.
# Usage: scripts/sweeps.sh [-j N] [name regex]
#   e.g. scripts/sweeps.sh FarFromNominal    scripts/sweeps.sh -j 2
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir=${INSDIAG_BUILD_DIR:-$root/build}
jobs=1
if [[ "${1:-}" == -j ]]; then
  jobs=$2
  shift 2
fi
pattern=${1:-.}
"$root/scripts/build.sh"
out=$build_dir/sweeps
mkdir -p "$out"
cd "$build_dir"
mapfile -t tests < <(ctest -N -L '^sweep$' -R "$pattern" | sed -n 's/^ *Test *#[0-9]*: //p')
if ((${#tests[@]} == 0)); then
  echo "no sweep test matches '$pattern'" >&2
  exit 1
fi
echo "${#tests[@]} sweep tests, $jobs at a time; logs in $out"
run_one() {
  local name=$1 log start status
  log="$1"
  log="$out/${log//\//_}.log"
  start=$(date +%s)
  # Each name as a whole: its dots and brackets matched literally.
  if ctest -L '^sweep$' -R "^$(printf '%s' "$name" | sed 's/[][().*+?^$|\\]/\\&/g')\$" -V >"$log" 2>&1; then
    status=passed
  else
    status=FAILED
  fi
  printf '%s  %s  %d s\n' "$status" "$name" $(($(date +%s) - start)) >>"$log"
}
export -f run_one
export out
printf '%s\0' "${tests[@]}" | xargs -0 -n 1 -P "$jobs" bash -c 'run_one "$0"'
failed=0
for name in "${tests[@]}"; do
  log="$out/${name//\//_}.log"
  tail -n 1 "$log"
  # The counts the test compared with its thresholds (ctest -V prefixes each line with the test's number).
  grep -E '\(at (least|most) [0-9]+\)' "$log" | sed -E 's/^[0-9]+: //; s/^/    /' || true
  tail -n 1 "$log" | grep -q '^passed' || failed=1
done
exit $failed
