#!/usr/bin/env bash
# Runs a command with a throwaway PostgreSQL cluster: initdb into a fresh
# directory, start on a unix socket only, export its location, run, stop, remove.
#   INSDIAG_TEST_PG_SOCKET_DIR  directory of the server's unix socket
#   INSDIAG_TEST_PG_PORT        the port number (only a socket name here)
#   INSDIAG_TEST_DATABASE_URL   libpq URL of the cluster's `postgres` database
# Usage: scripts/with-throwaway-pg.sh COMMAND [ARGS...]
set -euo pipefail
pg_bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
[[ -x "$pg_bin/initdb" ]] || { echo "with-throwaway-pg: no PostgreSQL server installed (scripts/install-deps.sh)" >&2; exit 1; }

cluster=$(mktemp -d /tmp/insdiag-pg.XXXXXX)
as_owner=()
if [[ $(id -u) -eq 0 ]]; then
  # initdb refuses to run as root: the cluster belongs to `postgres`.
  chown postgres: "$cluster"
  chmod 0755 "$cluster"
  as_owner=(runuser -u postgres --)
fi
port=$((20000 + RANDOM % 20000))
cleanup() {
  "${as_owner[@]}" "$pg_bin/pg_ctl" -D "$cluster/data" -m immediate stop >/dev/null 2>&1 || true
  rm -rf "$cluster"
}
trap cleanup EXIT INT TERM

"${as_owner[@]}" "$pg_bin/initdb" -D "$cluster/data" --no-sync -A trust -U postgres -E UTF8 >/dev/null
"${as_owner[@]}" "$pg_bin/pg_ctl" -D "$cluster/data" -w -l "$cluster/server.log" \
  -o "-c listen_addresses='' -k $cluster -p $port -c fsync=off -c synchronous_commit=off -c full_page_writes=off -c max_connections=200" \
  start >/dev/null

export INSDIAG_TEST_PG_SOCKET_DIR=$cluster
export INSDIAG_TEST_PG_PORT=$port
export INSDIAG_TEST_DATABASE_URL="postgresql://postgres@/postgres?host=$cluster&port=$port"
set +e
"$@"
status=$?
set -e
exit $status
