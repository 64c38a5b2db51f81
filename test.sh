#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test against a throwaway PostgreSQL.
# Usage: ./test.sh [ctest options...]   e.g. ./test.sh -L unit
set -euo pipefail
root=$(cd "$(dirname "$0")" && pwd)
"$root/scripts/install-deps.sh" --browser
"$root/scripts/build.sh"
cd "${INSDIAG_BUILD_DIR:-$root/build}"
exec "$root/scripts/with-throwaway-pg.sh" ctest --output-on-failure -j "$(nproc)" "$@"
