#!/usr/bin/env bash
# The fleet statistics benchmark (docs/PERFORMANCE.md): a throwaway
# PostgreSQL cluster, migrated and filled by insdiag-fleet with a generated
# fleet (10,000 units, 1,000,000 analyses by default), then every FleetService
# query timed by fleet_query_benchmark, and once more under auto_explain for
# the EXPLAIN (ANALYZE, BUFFERS) plans. Not part of ./test.sh.
#
# Usage: scripts/fleet-benchmark.sh [--units N] [--analyses N] [--repetitions N] [--out DIR]
# Results in DIR (default build/fleet-benchmark/): generate.txt (the
# generator's stages and summary), benchmark.md (the timings), plans.log.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${INSDIAG_BUILD_DIR:-$root/build}
units=10000
analyses=1000000
repetitions=20
out=$build/fleet-benchmark
while [[ $# -gt 0 ]]; do
  case $1 in
    --units) units=$2; shift 2 ;;
    --analyses) analyses=$2; shift 2 ;;
    --repetitions) repetitions=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "usage: $0 [--units N] [--analyses N] [--repetitions N] [--out DIR]" >&2; exit 2 ;;
  esac
done

if [[ ! -f $build/CMakeCache.txt ]]; then
  INSDIAG_BUILD_DIR=$build "$root/scripts/build.sh"
fi
export CCACHE_BASEDIR=$root
export CCACHE_DIR=${CCACHE_DIR:-$root/.cache/ccache}
cmake -S "$root" -B "$build" -DINSDIAG_BUILD_BENCHMARKS=ON >/dev/null
cmake --build "$build" --target insdiag-fleet fleet_query_benchmark
mkdir -p "$out"
chmod 0777 "$out"

export INSDIAG_FLEET_TOOL=$build/tools/insdiag-fleet
export INSDIAG_FLEET_BENCHMARK=$build/tests/benchmarks/fleet_query_benchmark
export INSDIAG_FLEET_ARGS="--units $units --analyses $analyses --seed 1 --end-time 2025-06-01"
export INSDIAG_FLEET_REPETITIONS=$repetitions
export INSDIAG_FLEET_OUT=$out
"$root/scripts/with-throwaway-pg.sh" bash -c '
  set -euo pipefail
  url="$INSDIAG_TEST_DATABASE_URL"
  psql=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -n 1)/psql
  "$psql" "$url" -qc "CREATE DATABASE fleet"
  fleet_url=$(sed "s|@/postgres?|@/fleet?|" <<< "$url")
  echo "== generating: insdiag-fleet $INSDIAG_FLEET_ARGS"
  /usr/bin/time -f "wall %e s, max RSS %M kB" "$INSDIAG_FLEET_TOOL" --database-url "$fleet_url" $INSDIAG_FLEET_ARGS \
    2>&1 | tee "$INSDIAG_FLEET_OUT/generate.txt"
  "$psql" "$fleet_url" -Atc "SELECT relname, pg_size_pretty(pg_total_relation_size(oid)) FROM pg_class
    WHERE relkind IN ('"'"'r'"'"', '"'"'m'"'"') AND relnamespace = '"'"'public'"'"'::regnamespace
    ORDER BY pg_total_relation_size(oid) DESC LIMIT 12" | tee -a "$INSDIAG_FLEET_OUT/generate.txt"
  echo "== timing every fleet query ($INSDIAG_FLEET_REPETITIONS repetitions)"
  status=0
  "$INSDIAG_FLEET_BENCHMARK" --database-url "$fleet_url" --repetitions "$INSDIAG_FLEET_REPETITIONS" \
    | tee "$INSDIAG_FLEET_OUT/benchmark.md" || status=$?
  echo "== plans (auto_explain: EXPLAIN ANALYZE, BUFFERS of every statement)"
  log="$INSDIAG_TEST_PG_SOCKET_DIR/server.log"
  lines=$(wc -l < "$log")
  PGOPTIONS="-c session_preload_libraries=auto_explain -c auto_explain.log_min_duration=0 -c auto_explain.log_analyze=on -c auto_explain.log_buffers=on -c auto_explain.log_timing=on" \
    "$INSDIAG_FLEET_BENCHMARK" --database-url "$fleet_url" --repetitions 1 --budget-ms 1e9 >/dev/null
  tail -n +"$((lines + 1))" "$log" > "$INSDIAG_FLEET_OUT/plans.log"
  echo "plans in $INSDIAG_FLEET_OUT/plans.log"
  exit $status
'
