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
seed() {  # seed FUZZER NAME CONTENT
  mkdir -p "$build/corpus/$1"
  printf '%b' "$3" >"$build/corpus/$1/$2"
}
python3 "$root/tests/fuzz/seeds_from_tests.py" "$build/corpus" >/dev/null
tests_build=${INSDIAG_BUILD_DIR:-$root/build}
if [[ -f $tests_build/build.ninja ]] && cmake --build "$tests_build" --target write_fuzz_seeds >/dev/null; then
  "$tests_build/tests/benchrun/write_fuzz_seeds" "$build/corpus/bench_run_csv_fuzzer"
else
  echo "fuzz.sh: no configured build in $tests_build: the tests' bench-run fixtures are not among the seeds" >&2
fi
head -n 40 "$tests_build/data/real/rlg-static-psins.csv" >"$build/corpus/bench_run_csv_fuzzer/real-record" 2>/dev/null ||
  rm -f "$build/corpus/bench_run_csv_fuzzer/real-record"
seed bench_run_csv_fuzzer spec-example '# format: insdiag-bench-run/1\n# unit_serial: INS-2000-0042\n# unit_type: INS-2000\n# site_latitude_deg: 55.5672\n# site_longitude_deg: 38.1500\n# site_height_m: 125.0\nt,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp\n0.0,1e-5,2e-5,-3e-5,0.01,-0.02,-9.81,0,0,0,25.0\n0.01,1e-5,2e-5,-3e-5,0.01,-0.02,-9.81,0,0,0,25.0\n'
# The gateway's own hostile cases: bytes gRPC refuses in metadata, an upload.
seed rest_gateway_fuzzer bad-authorization '- GET /v1/runs\nAuthorization: Bearer \xff\x01caf\xc3\xa9\n\n'
seed rest_gateway_fuzzer csv-upload "o POST /v1/runs:upload?requestId=r1\nContent-Type: text/csv\nAuthorization: Bearer t\n\n$(cat "$build/corpus/bench_run_csv_fuzzer/spec-example" 2>/dev/null)"
# The upload fuzzer's input is the bending of a valid stream, not data a test holds.
seed upload_stream_fuzzer valid '\x10\x04\xff\xff\xff\x00'
for dir in "$root"/tests/fuzz/regressions/*/; do
  [[ -d $dir ]] && cp "$dir"* "$build/corpus/$(basename "$dir")/" 2>/dev/null || true
done

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
