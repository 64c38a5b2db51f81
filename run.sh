#!/usr/bin/env bash
# Installs what is missing, builds, and starts insdiagd in the foreground on an
# embedded PostgreSQL kept in .insdiag/ inside this checkout. Ctrl-C stops both.
# Usage: ./run.sh [insdiagd options...]   e.g. ./run.sh --http-port 8081
# Environment: INSDIAG_GRPC_PORT (50051), INSDIAG_HTTP_PORT (8080),
#              INSDIAG_DATA_DIR (<checkout>/.insdiag)
set -euo pipefail
root=$(cd "$(dirname "$0")" && pwd)
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
build_dir=${INSDIAG_BUILD_DIR:-$root/build}

data_dir=${INSDIAG_DATA_DIR:-$root/.insdiag}
grpc_port=${INSDIAG_GRPC_PORT:-50051}
http_port=${INSDIAG_HTTP_PORT:-8080}
# The user's --data-dir, --grpc-port and --http-port replace these defaults
# (given twice, insdiagd would refuse); every other argument goes through.
user_data_dir=false
rest=()
while (($#)); do
  case $1 in
    --data-dir|--grpc-port|--http-port)
      (($# >= 2)) || { echo "run.sh: $1 needs a value" >&2; exit 2; }
      value=$2; flag=$1; shift 2 ;;
    --data-dir=*|--grpc-port=*|--http-port=*)
      value=${1#*=}; flag=${1%%=*}; shift ;;
    *) rest+=("$1"); shift; continue ;;
  esac
  case $flag in
    --data-dir) data_dir=$value; user_data_dir=true ;;
    --grpc-port) grpc_port=$value ;;
    --http-port) http_port=$value ;;
  esac
done

# As root, the embedded PostgreSQL runs as `postgres`, which must be able to
# enter every directory above the data directory (a checkout under /root is
# not reachable): fall back to /var/lib/insdiag then.
if [[ $(id -u) -eq 0 && -z "${INSDIAG_DATA_DIR:-}" ]] && ! $user_data_dir; then
  mkdir -p "$data_dir"
  if ! runuser -u postgres -- test -x "$data_dir"; then
    data_dir=/var/lib/insdiag
    echo "run.sh: the postgres user cannot reach $root; keeping the database in $data_dir" >&2
  fi
fi

cat <<EOM
insdiag is starting:
  page   http://localhost:$http_port/
  gRPC   localhost:$grpc_port   (health checking and reflection on)
  REST   http://localhost:$http_port/v1/runs   (health: http://localhost:$http_port/healthz)
  data   $data_dir
  token  on a new database, an admin token is written to $data_dir/admin-token:
         export INSDIAG_TOKEN=\$(cat $data_dir/admin-token)
  upload $build_dir/clients/insdiag upload RUN.csv --server localhost:$grpc_port
Stop with Ctrl-C.
EOM

exec "$build_dir/server/insdiagd" --data-dir "$data_dir" --grpc-port "$grpc_port" --http-port "$http_port" \
  "${rest[@]}"
