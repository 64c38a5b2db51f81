#!/usr/bin/env bash
# Runs Docker Compose with whichever this machine has: the `docker compose`
# plugin (v2) or the standalone `docker-compose` (v1, Debian 12's package).
#   scripts/compose.sh up -d      scripts/compose.sh down -v
# Without -f, the checkout's docker-compose.yml.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
if docker compose version >/dev/null 2>&1; then
  compose=(docker compose)
elif command -v docker-compose >/dev/null; then
  compose=(docker-compose)
else
  echo "compose.sh: neither 'docker compose' nor 'docker-compose' is installed (scripts/install-deps.sh --containers)" >&2
  exit 127
fi
files=()
[[ " $* " == *" -f "* || " $* " == *" --file "* || -n ${COMPOSE_FILE:-} ]] || files=(-f "$root/docker-compose.yml")
exec "${compose[@]}" "${files[@]}" "$@"
