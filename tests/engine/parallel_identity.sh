#!/bin/bash
# The analysis on every core reports exactly what it reports on one: a unit
# far from its type's nominal model (no datasheet), whose identification runs
# the likelihood grid, the starts and the information's second differences in
# parallel. Usage: parallel_identity.sh INSDIAG_CLI
set -euo pipefail
cli=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$cli" simulate "$dir/full.csv" --profile rotations --rate 10 --seed 104 --no-datasheet \
  --param gyro_bias_gm.x.sigma=4.848e-7 --param gyro_bias_gm.x.tau=200 > /dev/null
# The profile's first quarter hour (four and a half drift correlation times)
# takes every parallel path, the drift identified by likelihood among them,
# as the half hour does (the same stages in `--progress`) in 17 s instead of
# 40 s for the two analyses.
awk -F, 'header_seen && $1 > 900 { exit } { print } /^t,/ { header_seen = 1 }' "$dir/full.csv" > "$dir/run.csv"
INSDIAG_THREADS=1 "$cli" analyze "$dir/run.csv" --json --unit-type INS-2000 > "$dir/one.json"
INSDIAG_THREADS=4 "$cli" analyze "$dir/run.csv" --json --unit-type INS-2000 > "$dir/four.json"
if ! cmp -s "$dir/one.json" "$dir/four.json"; then
  echo "the reports on one and on four threads differ:" >&2
  diff "$dir/one.json" "$dir/four.json" | head -20 >&2
  exit 1
fi
grep -q '"verdict"' "$dir/one.json" || { echo "no report written" >&2; exit 1; }
echo "one and four threads: the same report ($(wc -c < "$dir/one.json") bytes)"
