#!/usr/bin/env bash
# Writes the fuzzers' seed corpora into CORPUS/<fuzzer>/: the REST paths,
# path templates, JSON bodies and CSV texts the tests spell out
# (seeds_from_tests.py); the bench runs the reader and server tests build in
# code (write_fuzz_seeds of the ordinary build TESTS_BUILD, when it is
# built); the real record's first lines (the build's import of data/real);
# the format's own example; and the inputs that once found a bug
# (regressions/). Shared by the fuzz campaign (scripts/fuzz.sh) and the
# suite's replay of every seed (fuzz_replay/*, tests/fuzz/CMakeLists.txt).
# Usage: tests/fuzz/write_seeds.sh CORPUS TESTS_BUILD
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
corpus=$1
tests_build=$2
seed() {  # seed FUZZER NAME CONTENT
  mkdir -p "$corpus/$1"
  printf '%b' "$3" >"$corpus/$1/$2"
}
python3 "$here/seeds_from_tests.py" "$corpus" >/dev/null
mkdir -p "$corpus/bench_run_csv_fuzzer" "$corpus/rest_gateway_fuzzer" "$corpus/upload_stream_fuzzer"
if [[ -x $tests_build/tests/benchrun/write_fuzz_seeds ]]; then
  "$tests_build/tests/benchrun/write_fuzz_seeds" "$corpus/bench_run_csv_fuzzer"
else
  echo "write_seeds.sh: no write_fuzz_seeds in $tests_build: the tests' bench-run fixtures are not among the seeds" >&2
fi
head -n 40 "$tests_build/data/real/rlg-static-psins.csv" >"$corpus/bench_run_csv_fuzzer/real-record" 2>/dev/null ||
  rm -f "$corpus/bench_run_csv_fuzzer/real-record"
seed bench_run_csv_fuzzer spec-example '# format: insdiag-bench-run/1\n# unit_serial: INS-2000-0042\n# unit_type: INS-2000\n# site_latitude_deg: 55.5672\n# site_longitude_deg: 38.1500\n# site_height_m: 125.0\nt,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw,temp\n0.0,1e-5,2e-5,-3e-5,0.01,-0.02,-9.81,0,0,0,25.0\n0.01,1e-5,2e-5,-3e-5,0.01,-0.02,-9.81,0,0,0,25.0\n'
# The gateway's own hostile cases: bytes gRPC refuses in metadata, an upload.
seed rest_gateway_fuzzer bad-authorization '- GET /v1/runs\nAuthorization: Bearer \xff\x01caf\xc3\xa9\n\n'
seed rest_gateway_fuzzer csv-upload "o POST /v1/runs:upload?requestId=r1\nContent-Type: text/csv\nAuthorization: Bearer t\n\n$(cat "$corpus/bench_run_csv_fuzzer/spec-example")"
# The upload fuzzer's input is the bending of a valid stream, not data a test holds.
seed upload_stream_fuzzer valid '\x10\x04\xff\xff\xff\x00'
for dir in "$here"/regressions/*/; do
  [[ -d $dir ]] && mkdir -p "$corpus/$(basename "$dir")" && cp "$dir"* "$corpus/$(basename "$dir")/"
done
exit 0
