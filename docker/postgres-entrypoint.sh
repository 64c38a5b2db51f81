#!/bin/bash
# Starts PostgreSQL 15 on PGDATA, making the cluster on first start:
#   POSTGRES_USER      the cluster's superuser (default postgres)
#   POSTGRES_PASSWORD  its password (required on first start; TCP clients
#                      authenticate with it, scram-sha-256)
#   POSTGRES_DB        a database made for it (default POSTGRES_USER)
#   PGPORT             TCP port (default 5432)
#   POSTGRES_LISTEN    listen_addresses (default 127.0.0.1: with host
#                      networking, the host's loopback only)
# Extra arguments go to postgres (e.g. -c max_connections=200).
set -euo pipefail
: "${PGDATA:=/var/lib/postgresql/data}"
user=${POSTGRES_USER:-postgres}
db=${POSTGRES_DB:-$user}
port=${PGPORT:-5432}
listen=${POSTGRES_LISTEN:-127.0.0.1}
say() { echo "postgres-entrypoint: $*" >&2; }

if [[ ! -s $PGDATA/PG_VERSION ]]; then
  [[ -w $PGDATA ]] || { say "$PGDATA is not writable by $(id -un)"; exit 1; }
  [[ -n ${POSTGRES_PASSWORD:-} ]] || { say "POSTGRES_PASSWORD is required to make the cluster"; exit 1; }
  say "first start: making the cluster in $PGDATA (superuser $user, database $db)"
  pwfile=$(mktemp)
  printf '%s\n' "$POSTGRES_PASSWORD" >"$pwfile"
  initdb -D "$PGDATA" -U "$user" --pwfile="$pwfile" -E UTF8 --locale=C.UTF-8 \
    --auth-local=peer --auth-host=scram-sha-256 >/dev/null
  rm -f "$pwfile"
  # Peer authentication maps the container's postgres user to the superuser.
  echo "local all $user peer map=insdiag" >"$PGDATA/pg_hba.conf.new"
  grep -v '^local' "$PGDATA/pg_hba.conf" >>"$PGDATA/pg_hba.conf.new"
  mv "$PGDATA/pg_hba.conf.new" "$PGDATA/pg_hba.conf"
  echo "insdiag postgres $user" >>"$PGDATA/pg_ident.conf"
  if [[ $db != postgres ]]; then
    pg_ctl -D "$PGDATA" -w -o "-c listen_addresses='' -p $port" start >/dev/null
    createdb -p "$port" -U "$user" "$db"
    pg_ctl -D "$PGDATA" -w -m fast stop >/dev/null
  fi
fi
say "listening on $listen:$port"
exec postgres -D "$PGDATA" -c listen_addresses="$listen" -p "$port" "$@"
