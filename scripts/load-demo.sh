#!/usr/bin/env bash
# Loads a small demonstration into a running insdiagd, so that a first look at
# the page shows the product at work rather than an empty list:
#   DEMO-1  a healthy INS-2000 unit on the rotations profile;
#   DEMO-2  a unit with a hidden gyro z scale-factor error (100 ppm), which
#           the analysis's loop finds and adds;
#   DEMO-3  a faulty unit: gyro x's bias steps by 0.6 °/h mid-run;
#   the real ring-laser-gyro record of data/real, imported from its PSINS
#           layout with `insdiag import --upload` and analysed;
#   a generated fleet of 40 units with their history, for the fleet views.
# Each simulated unit is uploaded and diagnosed (`insdiag diagnose`: the
# server walks the loop); the real record is uploaded and analysed.
#
# Usage: scripts/load-demo.sh --grpc HOST:PORT --http http://HOST:PORT
#          --token TOKEN --database-url URL [--build-dir DIR] [--work-dir DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir=${INSDIAG_BUILD_DIR:-$root/build}
grpc="" http="" token="" database_url="" work_dir=""
while (($#)); do
  case $1 in
    --grpc) grpc=$2; shift 2 ;;
    --http) http=$2; shift 2 ;;
    --token) token=$2; shift 2 ;;
    --database-url) database_url=$2; shift 2 ;;
    --build-dir) build_dir=$2; shift 2 ;;
    --work-dir) work_dir=$2; shift 2 ;;
    *) echo "load-demo.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
for required in grpc http token database_url; do
  [[ -n ${!required} ]] || { echo "load-demo.sh: --${required//_/-} is required" >&2; exit 2; }
done
cli=$build_dir/clients/insdiag
fleet_tool=$build_dir/tools/insdiag-fleet
if [[ -z $work_dir ]]; then
  work_dir=$(mktemp -d)
  trap 'rm -rf "$work_dir"' EXIT
fi
export INSDIAG_SERVER=$grpc INSDIAG_TOKEN=$token

say() { echo "insdiag demo: $*"; }

simulate_and_diagnose() {
  local serial=$1; shift
  "$cli" simulate "$work_dir/$serial.csv" --serial "$serial" "$@" >/dev/null
  say "$serial: uploading and diagnosing (the server walks the loop)"
  "$cli" diagnose "$work_dir/$serial.csv" >"$work_dir/$serial.diagnosis.txt"
  say "$serial: $(grep -m1 -v '^$' "$work_dir/$serial.diagnosis.txt" || true)"
}

# 20 Hz keeps each analysis to seconds; the rotations profile excites the
# gyro scale factors, the positions profile the biases.
simulate_and_diagnose DEMO-1 --profile rotations --rate 20 --seed 11
simulate_and_diagnose DEMO-2 --profile rotations --rate 20 --seed 12 --effect gyro_scale_factor.z=1e-4
simulate_and_diagnose DEMO-3 --profile positions --rate 20 --seed 13 --effect gyro_bias_step.x=3e-6@1500

# The real record, imported from the PSINS toolbox's layout as a bench's
# log would be (docs/IMPORT.md).
run=$("$cli" import "$root/data/real/rlg-static-psins.imu" --preset psins-imu --serial PSINS-RLG-2014 \
  --unit-type RLG-IMU --upload --request-id demo-real-record)
say "the real record is $run; analysing it"
curl -sS --fail-with-body -H "Authorization: Bearer $token" -H 'Content-Type: application/json' \
  -d "{\"run\": \"$run\"}" "$http/v1/analyses" >/dev/null

say "generating a fleet of 40 units with their history"
"$fleet_tool" --database-url "$database_url" --units 40 --seed 1 --serial-prefix DEMO-FLEET \
  >/dev/null 2>"$work_dir/fleet.log" || { cat "$work_dir/fleet.log" >&2; exit 1; }
say "done: open $http/"
