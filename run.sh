#!/usr/bin/env bash
# Installs what is missing, builds, and starts insdiagd in the foreground on an
# embedded PostgreSQL kept in .insdiag/ inside this checkout. Ctrl-C stops both.
# On a new database it then loads a small demonstration (scripts/load-demo.sh:
# simulated units, a faulty one, the real record, a fleet) while the server
# runs; --no-demo leaves the database empty.
# Usage: ./run.sh [--no-demo] [insdiagd options...]   e.g. ./run.sh --http-port 8081
# Environment: INSDIAG_GRPC_PORT (50051), INSDIAG_HTTP_PORT (8080),
#              INSDIAG_DATA_DIR (<checkout>/.insdiag), INSDIAG_BUILD_DIR (<checkout>/build),
#              INSDIAG_RUN_NO_BUILD=1 starts what INSDIAG_BUILD_DIR holds, without
#              installing or building first (its end-to-end test does so)
set -euo pipefail
root=$(cd "$(dirname "$0")" && pwd)
build_dir=${INSDIAG_BUILD_DIR:-$root/build}
if [[ ${INSDIAG_RUN_NO_BUILD:-} != 1 ]]; then
  "$root/scripts/install-deps.sh"
  "$root/scripts/build.sh"
fi

data_dir=${INSDIAG_DATA_DIR:-$root/.insdiag}
grpc_port=${INSDIAG_GRPC_PORT:-50051}
http_port=${INSDIAG_HTTP_PORT:-8080}
# The user's --data-dir, --grpc-port and --http-port replace these defaults
# (given twice, insdiagd would refuse); every other argument goes through.
user_data_dir=false
demo=true
database_url=""
rest=()
while (($#)); do
  case $1 in
    --no-demo) demo=false; shift; continue ;;
    --database-url) database_url=${2:-}; rest+=("$1" "${2:-}"); shift 2 || shift; continue ;;
    --database-url=*) database_url=${1#*=}; rest+=("$1"); shift; continue ;;
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

first_start=false
[[ -e $data_dir/admin-token ]] || first_start=true
"$build_dir/server/insdiagd" --data-dir "$data_dir" --grpc-port "$grpc_port" --http-port "$http_port" \
  "${rest[@]}" &
server=$!
trap 'kill -TERM $server 2>/dev/null; wait $server' INT TERM

if ! $demo && $first_start; then
  echo "run.sh: a new database; --no-demo: it stays empty"
fi
if $demo && $first_start; then
  for _ in $(seq 600); do
    curl -sf "http://localhost:$http_port/healthz" >/dev/null 2>&1 && break
    kill -0 $server 2>/dev/null || break
    sleep 0.5
  done
  if [[ -s $data_dir/admin-token ]]; then
    # The embedded cluster listens on a socket in DATA_DIR/run only.
    url=${database_url:-"host='$data_dir/run' port=5432 user=postgres dbname='insdiag'"}
    echo "run.sh: a new database: loading the demonstration (log: $data_dir/demo.log; --no-demo to skip)"
    "$root/scripts/load-demo.sh" --grpc "localhost:$grpc_port" --http "http://localhost:$http_port" \
      --token "$(cat "$data_dir/admin-token")" --database-url "$url" --build-dir "$build_dir" \
      >"$data_dir/demo.log" 2>&1 &&
      echo "run.sh: the demonstration is loaded: open http://localhost:$http_port/ (units DEMO-1, DEMO-2, DEMO-3)" ||
      echo "run.sh: the demonstration did not load; see $data_dir/demo.log" &
  fi
fi
wait $server
