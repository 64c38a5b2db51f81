#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with clang in build-fuzz/, seeds
# their corpora from the tests, runs each for SECONDS from its seeds (the
# corpus of an earlier run is not kept), and prints one line per fuzzer:
# seeds, executions, coverage (edges), corpus size and whether it found
# anything. A finding leaves its input in build-fuzz/findings/<fuzzer>/ and
# makes the script fail.
# Seeds: the REST paths, path templates, JSON bodies and CSV texts the tests
# spell out (tests/fuzz/seeds_from_tests.py); the bench runs the reader and
# server tests build in code (write_fuzz_seeds, built in the ordinary build,
# $INSDIAG_BUILD_DIR or build/, when it is configured); the real record's
# first lines (the build's import of data/real, tests/CMakeLists.txt) and
# the format's own example; inputs that once found a bug
# (tests/fuzz/regressions/), run first every time.
# Usage: scripts/fuzz.sh [SECONDS] [FUZZER...]   (default 60 s each, all five)
# The figures in docs/RELIABILITY.md come from `scripts/fuzz.sh 60`.
set -euo pipefail
root=$(cd "$(dirname "$0")" && pwd)/..
seconds=${1:-60}
shift || true
fuzzers=("$@")
((${#fuzzers[@]})) || fuzzers=(bench_run_csv_fuzzer json_request_fuzzer rest_request_fuzzer rest_gateway_fuzzer upload_stream_fuzzer)
build=${INSDIAG_FUZZ_BUILD_DIR:-$root/build-fuzz}

if [[ ! -f $build/build.ninja ]]; then
  # -O1, the usual optimisation for fuzzing; line tables for the sanitizers' reports.
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DINSDIAG_FUZZ=ON \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DINSDIAG_BUILD_TESTS=OFF -DINSDIAG_BUILD_BENCHMARKS=OFF >/dev/null
fi
cmake --build "$build" --target "${fuzzers[@]}" >/dev/null

rm -rf "$build/corpus"
tests_build=${INSDIAG_BUILD_DIR:-$root/build}
if [[ -f $tests_build/build.ninja ]] && ! cmake --build "$tests_build" --target write_fuzz_seeds >/dev/null; then
  echo "fuzz.sh: write_fuzz_seeds did not build in $tests_build" >&2
fi
"$root/tests/fuzz/write_seeds.sh" "$build/corpus" "$tests_build"

status=0
printf '%-24s %6s %12s %8s %8s %s\n' fuzzer seeds executions edges corpus finding
for f in "${fuzzers[@]}"; do
  mkdir -p "$build/findings/$f" "$build/corpus/$f"
  seeds=$(find "$build/corpus/$f" -type f | wc -l)
  log="$build/findings/$f.log"
  if "$build/tests/fuzz/$f" -max_total_time="$seconds" -print_final_stats=1 -rss_limit_mb=2048 -timeout=20 \
      -artifact_prefix="$build/findings/$f/" "$build/corpus/$f" >"$log" 2>&1; then
    finding=none
  else
    finding="see $log"
    status=1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
  edges=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo '?')
  corpus=$(find "$build/corpus/$f" -type f | wc -l)
  printf '%-24s %6s %12s %8s %8s %s\n' "$f" "$seeds" "$execs" "$edges" "$corpus" "$finding"
done
exit $status
