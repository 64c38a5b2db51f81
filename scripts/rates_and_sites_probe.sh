#!/usr/bin/env bash
# Healthy and faulty units at rates, latitudes and unit classes outside the
# fault matrix (20, 25 and 200 Hz; the equator to 80°; units labelled with a
# unit type they do not match), one hour each, on the independent simulator.
# Prints one line a run: the verdict and the candidates significant at
# family-wise 1 % (Holm). docs/FAULT_SCENARIOS.md has the figures.
#
# Usage: scripts/rates_and_sites_probe.sh [OUT_DIR]   (INSDIAG_CLI: the CLI to use)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$(mktemp -d)}
cli=${INSDIAG_CLI:-$root/build/clients/insdiag}
mkdir -p "$out"

# name preset profile rate_hz latitude_deg seed datasheet [fault]
# (`--datasheet no` keeps the simulator's unit type, INS-2000: a unit far from it)
cases='h01 nav positions 20 70 21 yes
h02 nav turns 25 -35 22 yes
h03 nav mixed 200 0 23 yes
h04 tactical positions 20 45 24 no
h05 tactical mixed 10 -60 25 no
h06 mems static 25 30 26 no
h07 mems mixed 200 55 27 no
h08 nav mixed 10 80 28 yes
h09 tactical-0.1 turns 50 -10 29 yes
h10 nav static 100 55 30 yes
h11 nav positions 200 -45 41 yes
f01 tactical-0.1 positions 20 45 31 yes gyro_bias_step.y=2.9e-6@1234.5
f02 tactical-0.1 mixed 25 45 32 yes gyro_bias_step.x=-2.9e-6@2100.2
f03 tactical mixed 200 45 33 yes acc_bias_step.z=0.05@1800.7
f04 nav mixed 20 -35 34 yes acc_bias_ramp.x=1.47e-6@1500
f05 mems static 25 45 35 no gyro_bias_step.x=2.4e-4@1700
f06 nav positions 10 70 36 yes gyro_bias_ramp.y=2.4e-10@1200
f07 tactical-0.1 mixed 200 45 37 yes gyro_bias_step.z=2.9e-6@900
f08 tactical positions 20 -20 38 no acc_bias_step.x=-0.05@2500'

run_case() {
  local name=$1 preset=$2 profile=$3 rate=$4 lat=$5 seed=$6 datasheet=$7 fault=${8:-}
  local csv="$out/$name.csv" report="$out/$name.txt"
  /usr/bin/python3 "$root/tests/benchsim/benchsim.py" --out "$csv" --preset "$preset" --profile "$profile" \
    --rate-hz "$rate" --duration 3600 --seed "$seed" --latitude-deg "$lat" --datasheet "$datasheet" \
    ${fault:+--fault "$fault"} >/dev/null
  "$cli" analyze "$csv" >"$report" 2>&1 || true
  local significant
  significant=$(sed -n '/^missing effects/,/^$/p' "$report" | grep '(Holm)' |
    sed -E 's/^ *([^ ]+).* p ([0-9.e+-]+) \(Holm\).*/\1 \2/' | awk '$2 + 0 < 0.01 {printf "%s (p %s) ", $1, $2}')
  echo "$name $preset $profile ${rate} Hz, latitude $lat, seed $seed, datasheet $datasheet, ${fault:-healthy} | $(grep -m1 '^verdict' "$report") | significant: ${significant:-none}"
  rm -f "$csv"
}
export -f run_case
export root out cli
echo "$cases" | xargs -P "$(nproc)" -L 1 bash -c 'run_case "$@"' _
