#!/usr/bin/env bash
# The fleet statistics and the listings read from a PostgreSQL streaming
# replica (insdiagd --read-database-url), writes going to the primary:
#  1. a primary cluster and its streaming replica (pg_basebackup -R), both on
#     unix sockets only, in a fresh directory;
#  2. insdiagd on the primary, its reads on the replica, one worker
#     refreshing the fleet views every second;
#  3. a run uploaded: the fleet statistics served count it once the replica
#     has replayed the primary's refresh;
#  4. the replica's replay paused, a second run uploaded: the primary's views
#     count two runs, the statistics and the run listing served still one —
#     the reads come from the replica, and the writes did not need it;
#  5. replay resumed: the statistics and the listing served count two;
#  6. the replica stopped: fleet queries are refused as unavailable (503),
#     uploads are still stored; the replica started again: the server
#     reconnects and serves the statistics with the third run.
# Usage: tests/server/read_replica_test.sh BUILD_DIR
set -euo pipefail
build_dir=$(cd "${1:?usage: read_replica_test.sh BUILD_DIR}" && pwd)
pg_bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
[[ -x "$pg_bin/pg_basebackup" ]] || { echo "read replica test: no PostgreSQL server installed" >&2; exit 1; }
cli=$build_dir/clients/insdiag

say() { echo "read replica test: $(date +%T) $*"; }
fail() { echo "read replica test: FAILED: $*" >&2; exit 1; }
# shellcheck source=wait_until.sh
source "$(dirname "${BASH_SOURCE[0]}")/wait_until.sh"

work=$(mktemp -d /tmp/insdiag-replica.XXXXXX)
chmod 0755 "$work"
as_owner=()
if [[ $(id -u) -eq 0 ]]; then
  # initdb refuses root: the clusters belong to `postgres`.
  chown postgres: "$work"
  as_owner=(runuser -u postgres --)
fi
primary_port=$((20000 + RANDOM % 20000))
replica_port=$((primary_port + 1))
server_pid=
cleanup() {
  [[ -n $server_pid ]] && kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null
  for cluster in replica primary; do
    "${as_owner[@]}" "$pg_bin/pg_ctl" -D "$work/$cluster" -m immediate stop >/dev/null 2>&1 || true
  done
  rm -rf "$work"
}
trap cleanup EXIT INT TERM

start_cluster() {  # NAME PORT
  "${as_owner[@]}" "$pg_bin/pg_ctl" -D "$work/$1" -w -l "$work/$1.log" \
    -o "-c listen_addresses='' -k $work -p $2 -c fsync=off" start >/dev/null
}
psql_at() {  # PORT SQL
  "${as_owner[@]}" "$pg_bin/psql" -X -q -A -t -h "$work" -p "$1" -U postgres -d insdiag -c "$2"
}

"${as_owner[@]}" "$pg_bin/initdb" -D "$work/primary" --no-sync -A trust -U postgres -E UTF8 >/dev/null
start_cluster primary "$primary_port"
"${as_owner[@]}" "$pg_bin/psql" -X -q -h "$work" -p "$primary_port" -U postgres -d postgres \
  -c "CREATE DATABASE insdiag" >/dev/null
"${as_owner[@]}" "$pg_bin/pg_basebackup" -h "$work" -p "$primary_port" -U postgres -D "$work/replica" -R -X stream -c fast
start_cluster replica "$replica_port"
[[ $(psql_at "$replica_port" "SELECT pg_is_in_recovery()") == t ]] || fail "the replica is not a standby"
say "primary on port $primary_port, streaming replica on $replica_port (sockets in $work)"

url() { echo "postgresql://postgres@/insdiag?host=$work&port=$1"; }
mkdir -p "$work/data"
"$build_dir/server/insdiagd" --database-url "$(url "$primary_port")" \
  --read-database-url "$(url "$replica_port")" --data-dir "$work/data" \
  --grpc-port 0 --http-port 0 --workers 1 --fleet-refresh-seconds 1 \
  >"$work/insdiagd.out" 2>"$work/insdiagd.err" &
server_pid=$!
listening() { grep -qs "insdiagd: listening" "$work/insdiagd.out"; }
wait_until 60 "insdiagd listens (its log: $work/insdiagd.err)" listening
grep -q "reads=replica" "$work/insdiagd.out" || fail "insdiagd does not say it reads from the replica"
grpc=$(sed -n 's/.*grpc=[^ ]*:\([0-9]*\) .*/\1/p' "$work/insdiagd.out")
http=$(sed -n 's/.*http=[^ ]*:\([0-9]*\) .*/\1/p' "$work/insdiagd.out")
export INSDIAG_SERVER=127.0.0.1:$grpc INSDIAG_TOKEN
INSDIAG_TOKEN=$(cat "$work/data/admin-token")

served_runs() {
  curl -sS --fail -H "Authorization: Bearer $INSDIAG_TOKEN" "http://127.0.0.1:$http/v1/fleetStatistics" |
    python3 -c 'import json, sys; print(int(json.load(sys.stdin).get("runCount", 0)))'
}
listed_runs() {
  curl -sS --fail -H "Authorization: Bearer $INSDIAG_TOKEN" "http://127.0.0.1:$http/v1/runs?pageSize=100" |
    python3 -c 'import json, sys; print(len(json.load(sys.stdin).get("runs", [])))'
}
primary_runs() { psql_at "$primary_port" "SELECT coalesce(sum(runs), 0) FROM fleet_counts"; }
served_is() { [[ $(served_runs) == "$1" ]]; }
primary_is() { [[ $(primary_runs) == "$1" ]]; }
upload() {
  "$cli" simulate "$work/$1.csv" --profile static --rate 10 --seed "$2" --serial "$1" >/dev/null
  "$cli" upload "$work/$1.csv" >/dev/null
}

upload REPLICA-1 1
wait_until 30 "the primary's fleet views count the first run" primary_is 1
wait_until 30 "the statistics served count the first run" served_is 1
say "one run, counted on the primary and served from the replica"

psql_at "$replica_port" "SELECT pg_wal_replay_pause()" >/dev/null
paused() { [[ $(psql_at "$replica_port" "SELECT pg_get_wal_replay_pause_state()") == paused ]]; }
wait_until 10 "the replica's replay pauses" paused
upload REPLICA-2 2
wait_until 30 "the primary's fleet views count the second run" primary_is 2
for _ in 1 2 3; do
  served_is 1 || fail "the statistics served counted the second run while the replica's replay was paused: they are not read from the replica"
  [[ $(listed_runs) == 1 ]] || fail "the run listing showed the second run while the replica's replay was paused: it is not read from the replica"
  sleep 1
done
say "replay paused: the primary counts 2 runs, the statistics and the listing served still 1"

psql_at "$replica_port" "SELECT pg_wal_replay_resume()" >/dev/null
wait_until 30 "the statistics served count the second run after replay resumed" served_is 2
listed_is() { [[ $(listed_runs) == "$1" ]]; }
wait_until 30 "the run listing shows the second run after replay resumed" listed_is 2
say "replay resumed: the statistics served count 2 runs"

# The replica down: fleet queries are refused as unavailable, the rest goes on.
"${as_owner[@]}" "$pg_bin/pg_ctl" -D "$work/replica" -m immediate stop >/dev/null
for attempt in 1 2; do
  code=$(curl -sS -o "$work/answer.json" -w '%{http_code}' -H "Authorization: Bearer $INSDIAG_TOKEN" \
    "http://127.0.0.1:$http/v1/fleetStatistics")
  [[ $code == 503 ]] || fail "with the replica down, GET /v1/fleetStatistics (attempt $attempt) answered $code, not 503: $(cat "$work/answer.json")"
done
upload REPLICA-3 3
wait_until 30 "with the replica down, the primary's fleet views count the third run" primary_is 3
say "replica down: fleet statistics 503, uploads stored on the primary"
start_cluster replica "$replica_port"
wait_until 60 "the replica is back and the statistics served count the third run" served_is 3
say "replica back: the statistics served count 3 runs"

kill -TERM "$server_pid"
wait "$server_pid" || fail "insdiagd did not stop cleanly: $(tail -n 5 "$work/insdiagd.err")"
server_pid=
say "passed"
