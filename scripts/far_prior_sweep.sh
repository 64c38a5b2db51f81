#!/usr/bin/env bash
# Usage: scripts/far_prior_sweep.sh SEED   (e.g. seq 101 110 | xargs -P 2 -n 1 scripts/far_prior_sweep.sh)
# Writes /tmp/far/fSEED.json, the report of one seed of "a unit far from its type's nominal model": gyro drifts σ 0.1 °/h (10 × INS-2000), τ 200 s, no datasheet.
set -euo pipefail
s=$1
mkdir -p /tmp/far
S=4.84813681109536e-07
P=""; for a in x y z; do P="$P --param gyro_bias_gm.$a.sigma=$S --param gyro_bias_gm.$a.tau=200"; done
"$(dirname "$0")/../build/clients/insdiag" simulate /tmp/far/f$s.csv --profile rotations --rate 50 --seed $s $P --no-datasheet >/dev/null 2>&1
"$(dirname "$0")/../build/clients/insdiag" analyze /tmp/far/f$s.csv --json > /tmp/far/f$s.json 2>/dev/null
rm -f /tmp/far/f$s.csv
