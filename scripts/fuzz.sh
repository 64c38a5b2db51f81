#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with clang in build-fuzz/, seeds
# their corpora from the project's own inputs, runs each for SECONDS, and
# prints one line per fuzzer: executions, coverage (edges), corpus size and
# whether it found anything. A finding leaves its input in
# build-fuzz/findings/<fuzzer>/ and makes the script fail.
# Usage: scripts/fuzz.sh [SECONDS] [FUZZER...]   (default 60 s each, all four)
# The figures in docs/RELIABILITY.md come from `scripts/fuzz.sh 600`.
set -euo pipefail
root=$(cd "$(dirname "$0")" && pwd)/..
seconds=${1:-60}
shift || true
fuzzers=("$@")
((${#fuzzers[@]})) || fuzzers=(bench_run_csv_fuzzer json_request_fuzzer rest_request_fuzzer upload_stream_fuzzer)
build=${INSDIAG_FUZZ_BUILD_DIR:-$root/build-fuzz}

if [[ ! -f $build/build.ninja ]]; then
  # -O1, the usual optimisation for fuzzing; line tables for the sanitizers' reports.
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DINSDIAG_FUZZ=ON \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DINSDIAG_BUILD_TESTS=OFF -DINSDIAG_BUILD_BENCHMARKS=OFF >/dev/null
fi
cmake --build "$build" --target "${fuzzers[@]}" >/dev/null

# Seeds: the real record's first lines, the format's own example, REST and JSON shapes.
seed() {  # seed FUZZER NAME CONTENT
  mkdir -p "$build/corpus/$1"
  printf '%b' "$3" >"$build/corpus/$1/$2"
}
mkdir -p "$build/corpus/bench_run_csv_fuzzer"
head -n 40 "${INSDIAG_BUILD_DIR:-$root/build}/data/real/rlg-static-psins.csv" >"$build/corpus/bench_run_csv_fuzzer/real-record" 2>/dev/null || true
seed bench_run_csv_fuzzer spec-example '# format: insdiag-bench-run/1\n# unit_serial: INS-2000-0042\n# unit_type: INS-2000\n# site_latitude_deg: 55.5672\n# site_longitude_deg: 38.1500\n# site_height_m: 125.0\nt,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp\n0.0,1e-5,2e-5,-3e-5,0.01,-0.02,-9.81,0,0,0,25.0\n0.01,1e-5,2e-5,-3e-5,0.01,-0.02,-9.81,0,0,0,25.0\n'
seed json_request_fuzzer create-analysis '\x05{"analysis":{"run":"runs/7c1e0000-0000-4000-8000-000000000000","model":{"effects":["gyro_scale_factor.z"]}},"requestId":"x"}'
seed json_request_fuzzer list-runs '\x01{"pageSize":5,"pageToken":"abc","unitSerial":"INS-1"}'
seed json_request_fuzzer create-token '\x1e{"token":{"displayName":"bench","role":"OPERATOR","expireTime":"2030-01-01T00:00:00Z"}}'
seed rest_request_fuzzer get-run '/v1/{name=runs/*}\n/v1/runs/7c1e\npageSize=5&pageToken=x\n{"analysis":{"run":"runs/x"}}'
seed rest_request_fuzzer nested '/v1/{unit_type=unitTypes/*}/parameterTrends\n/v1/unitTypes/INS-2000/parameterTrends\nanalysis.model.effects=gyro_scale_factor.x&token.role=ADMIN\n{"token":{"displayName":"x"}}'
seed upload_stream_fuzzer valid '\x10\x04\xff\xff\xff\x00'
# Inputs that once found a bug run first, every time (tests/fuzz/regressions).
for dir in "$root"/tests/fuzz/regressions/*/; do
  [[ -d $dir ]] && cp "$dir"* "$build/corpus/$(basename "$dir")/" 2>/dev/null || true
done

status=0
printf '%-24s %12s %8s %8s %s\n' fuzzer executions edges corpus finding
for f in "${fuzzers[@]}"; do
  mkdir -p "$build/findings/$f" "$build/corpus/$f"
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
  printf '%-24s %12s %8s %8s %s\n' "$f" "$execs" "$edges" "$corpus" "$finding"
done
exit $status
