#!/usr/bin/env bash
# The `container` test: docker-compose.yml as a factory would run it.
#  1. builds the images (scripts/container-images.sh: the Debian base image,
#     cached; PostgreSQL 15; insdiagd from BUILD_DIR's binaries);
#  2. brings the composition up under its own project name and ports
#     (PostgreSQL 55439, gRPC 55051, HTTP 58080) and waits until both
#     containers are healthy;
#  3. checks that the three ports listen on 127.0.0.1 only;
#  4. with the insdiag CLI of BUILD_DIR and the admin token the containerised
#     insdiagd wrote: simulates a faulty unit (gyro x bias step), uploads it,
#     analyses it walking the loop (REST, POST /v1/analyses with discover, as
#     `insdiag diagnose` does; polled until SUCCEEDED: verdict
#     FAULTY), diagnoses the analysis (gyro.x first), and finds the run, the
#     analysis and the diagnosis in the containerised PostgreSQL;
#  5. runs one of the project's own `db` test programs against the
#     containerised PostgreSQL (INSDIAG_TEST_DATABASE_URL), as a factory's CI
#     would run its integration tests;
#  6. tears the composition down with its volumes (also on failure, after
#     printing the containers' logs).
# Skipped (exit 77, ctest's SKIP_RETURN_CODE) when no Docker engine answers:
# no `docker` command, or `docker info` fails within 20 s.
#
# Usage: tests/container/compose_test.sh [BUILD_DIR]    (default <checkout>/build)
# Environment: INSDIAG_CONTAINER_TEST_PG_PORT, _GRPC_PORT, _HTTP_PORT change the ports.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build_dir=${1:-$root/build}
build_dir=$(cd "$build_dir" && pwd)
project=insdiag-container-test
pg_port=${INSDIAG_CONTAINER_TEST_PG_PORT:-55439}
grpc_port=${INSDIAG_CONTAINER_TEST_GRPC_PORT:-55051}
http_port=${INSDIAG_CONTAINER_TEST_HTTP_PORT:-58080}
image=insdiag:container-test
cli=$build_dir/clients/insdiag

say() { echo "container test: $*"; }
fail() { echo "container test: FAILED: $*" >&2; exit 1; }
skip() { echo "container test: SKIPPED: $*"; exit 77; }

# --- Is there a Docker engine? -------------------------------------------
command -v docker >/dev/null ||
  skip "no docker command on this machine (scripts/install-deps.sh --containers installs Debian's docker.io; then start dockerd)"
if ! info=$(timeout 20 docker info 2>&1 >/dev/null); then
  skip "no Docker engine answers ('docker info' failed: $(echo "$info" | grep -v '^\s*$' | tail -n 1)); start dockerd to run this test"
fi
compose_cmd=()
if docker compose version >/dev/null 2>&1; then
  compose_cmd=(docker compose)
elif command -v docker-compose >/dev/null; then
  compose_cmd=(docker-compose)
else
  fail "a Docker engine answers but neither 'docker compose' nor 'docker-compose' is installed (scripts/install-deps.sh --containers)"
fi
[[ -x $cli ]] || fail "no $cli: build first (scripts/build.sh)"

port_in_use() { (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
work=$(mktemp -d /tmp/insdiag-container-test.XXXXXX)
export INSDIAG_IMAGE=$image INSDIAG_PG_PORT=$pg_port INSDIAG_GRPC_PORT=$grpc_port INSDIAG_HTTP_PORT=$http_port
compose() { "${compose_cmd[@]}" -f "$root/docker-compose.yml" -p "$project" "$@"; }
up=false
teardown() {
  local status=$?
  if $up; then
    if ((status != 0)); then
      echo "--- container logs (postgres) ---" >&2; compose logs --no-color --tail 60 postgres >&2 || true
      echo "--- container logs (insdiagd) ---" >&2; compose logs --no-color --tail 60 insdiagd >&2 || true
    fi
    local started=$SECONDS
    compose down -v --remove-orphans >"$work/down.log" 2>&1 || cat "$work/down.log" >&2
    say "composition down, volumes removed ($((SECONDS - started)) s)"
  fi
  rm -rf "$work"
  exit $status
}
trap teardown EXIT
trap 'exit 130' INT TERM
test_started=$SECONDS

# A composition left over from an interrupted run goes first.
compose down -v --remove-orphans >/dev/null 2>&1 || true
for port in "$pg_port" "$grpc_port" "$http_port"; do
  port_in_use "$port" && fail "127.0.0.1:$port is in use by another process; set INSDIAG_CONTAINER_TEST_*_PORT"
done

# --- 1. Images ------------------------------------------------------------
started=$SECONDS
"$root/scripts/container-images.sh" --build-dir "$build_dir"
say "images ready in $((SECONDS - started)) s"

# --- 2. Up -----------------------------------------------------------------
started=$SECONDS
up=true
compose up -d >"$work/up.log" 2>&1 || { cat "$work/up.log" >&2; fail "'${compose_cmd[*]} up -d' failed"; }
container_of() { compose ps -q "$1"; }
health_of() { docker inspect -f '{{ if .State.Health }}{{ .State.Health.Status }}{{ else }}{{ .State.Status }}{{ end }}' "$1" 2>/dev/null; }
postgres_container=$(container_of postgres)
server_container=$(container_of insdiagd)
[[ -n $postgres_container && -n $server_container ]] || fail "the composition did not create both containers"
for _ in $(seq 240); do
  pg_health=$(health_of "$postgres_container") server_health=$(health_of "$server_container")
  [[ $pg_health == healthy && $server_health == healthy ]] && break
  [[ $(docker inspect -f '{{.State.Running}}' "$server_container") == true ]] ||
    fail "insdiagd's container stopped ($(docker inspect -f '{{.State.Status}} {{.State.ExitCode}}' "$server_container"))"
  sleep 0.5
done
[[ $pg_health == healthy && $server_health == healthy ]] ||
  fail "not healthy after 120 s (postgres: $pg_health, insdiagd: $server_health)"
say "composition up and healthy in $((SECONDS - started)) s (PostgreSQL 127.0.0.1:$pg_port, gRPC 127.0.0.1:$grpc_port, HTTP 127.0.0.1:$http_port)"

# --- 3. Loopback only --------------------------------------------------------
# With host networking the containers' sockets are the host's: every listener
# on the three ports must be bound to 127.0.0.1.
for port in "$pg_port" "$grpc_port" "$http_port"; do
  hex=$(printf '%04X' "$port")
  listeners=$(awk -v p=":$hex" '$4 == "0A" && substr($2, length($2) - 4) == p {print $2}' /proc/net/tcp /proc/net/tcp6)
  [[ -n $listeners ]] || fail "nothing listens on port $port"
  while read -r address; do
    # 127.0.0.1, in /proc/net/tcp or IPv4-mapped (::ffff:127.0.0.1) in tcp6.
    [[ $address == "0100007F:$hex" || $address == "0000000000000000FFFF00000100007F:$hex" ]] ||
      fail "port $port listens on $address, not 127.0.0.1 only"
  done <<<"$listeners"
done
say "ports $pg_port, $grpc_port and $http_port listen on 127.0.0.1 only"

# --- 4. Upload -> analysis -> diagnosis ------------------------------------------
token=$(docker exec "$server_container" cat /var/lib/insdiag/admin-token) ||
  fail "no admin token in insdiagd's container (/var/lib/insdiag/admin-token)"
export INSDIAG_SERVER=127.0.0.1:$grpc_port INSDIAG_TOKEN=$token
http=http://127.0.0.1:$http_port
json_field() { python3 -c 'import json, sys; v = json.load(sys.stdin); [v := v[k] for k in sys.argv[1:]]; print(v)' "$@"; }
started=$SECONDS
serial=CONTAINER-TEST-1
"$cli" simulate "$work/run.csv" --serial "$serial" --profile positions --rate 20 --seed 13 \
  --effect gyro_bias_step.x=3e-6@1500 >/dev/null
run=$("$cli" upload "$work/run.csv" --request-id "container-test-$$")
[[ $run == runs/* ]] || fail "upload printed '$run', not a run's name"
say "uploaded $serial: $run"
curl -sS --fail-with-body -H "Authorization: Bearer $token" -H 'Content-Type: application/json' \
  -d "{\"run\": \"$run\", \"discover\": true}" "$http/v1/analyses" >"$work/analysis.json" ||
  fail "POST /v1/analyses: $(cat "$work/analysis.json")"
analysis=$(json_field name <"$work/analysis.json")
[[ $analysis == analyses/* ]] || fail "POST /v1/analyses returned no analysis: $(cat "$work/analysis.json")"
state=""
for _ in $(seq 600); do
  curl -sS --fail-with-body -H "Authorization: Bearer $token" "$http/v1/$analysis" >"$work/analysis.json" ||
    fail "GET /v1/$analysis: $(cat "$work/analysis.json")"
  state=$(json_field state <"$work/analysis.json")
  [[ $state == SUCCEEDED || $state == FAILED || $state == CANCELLED ]] && break
  sleep 0.5
done
[[ $state == SUCCEEDED ]] || fail "$analysis ended $state: $(head -c 2000 "$work/analysis.json")"
verdict=$("$cli" report "$analysis" --json | json_field verdict)
say "$analysis SUCCEEDED in the container's worker, verdict $verdict"
[[ $verdict == FAULTY ]] || fail "the faulty unit's verdict is $verdict, not FAULTY"
"$cli" diagnoses create "$analysis" --json >"$work/diagnosis.json"
diagnosis=$(json_field name <"$work/diagnosis.json")
[[ $diagnosis == diagnoses/* ]] || fail "diagnoses create returned no diagnosis: $(head -c 2000 "$work/diagnosis.json")"
modules=$(python3 -c 'import json, sys; print(" ".join(c["module"] for c in json.load(sys.stdin).get("candidates", [])))' <"$work/diagnosis.json")
say "$diagnosis: probable faulty modules, most probable first: $modules"
[[ ${modules%% *} == gyro.x ]] || fail "the diagnosis does not put gyro x first: $modules"
say "upload -> analysis -> diagnosis in $((SECONDS - started)) s"

# The rows are in the containerised PostgreSQL.
counts=$(docker exec "$postgres_container" psql -X -qtA -U insdiag -d insdiag -c \
  "SELECT (SELECT count(*) FROM runs) || ' ' || (SELECT count(*) FROM analyses WHERE state = 'SUCCEEDED') || ' ' || (SELECT count(*) FROM diagnoses)" 2>&1) ||
  fail "psql in the PostgreSQL container: $counts"
[[ $counts == "1 1 1" ]] || fail "the containerised PostgreSQL holds runs, succeeded analyses, diagnoses: $counts, not 1 1 1"
say "the containerised PostgreSQL holds the run, the analysis and the diagnosis"

# --- 5. The project's db tests against the containerised PostgreSQL -------------
db_test=$build_dir/tests/kb/kb_run_store_test
if [[ -x $db_test ]]; then
  started=$SECONDS
  INSDIAG_TEST_DATABASE_URL="postgresql://insdiag:insdiag@127.0.0.1:$pg_port/postgres" \
    "$db_test" --gtest_brief=1 >"$work/db_test.log" 2>&1 || { cat "$work/db_test.log" >&2; fail "$db_test against the containerised PostgreSQL"; }
  grep -q 'SKIPPED' "$work/db_test.log" && { cat "$work/db_test.log" >&2; fail "$db_test skipped its tests"; }
  say "$(basename "$db_test") passed against the containerised PostgreSQL in $((SECONDS - started)) s ($(grep -o '[0-9]* tests\? from [0-9]* test suites\? ran' "$work/db_test.log" | head -n 1))"
else
  say "no $db_test in this build (INSDIAG_BUILD_TESTS=OFF?): the db tests' step is left out"
fi
say "passed in $((SECONDS - test_started)) s"
