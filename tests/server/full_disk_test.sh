#!/usr/bin/env bash
# A full disk loses nothing acknowledged and stores nothing half-done:
#  1. a tmpfs of a fixed size (160 MB) holds insdiagd's data directory and its
#     embedded PostgreSQL;
#  2. bench runs of 360,000 samples (54 MB of CSV, about 32 MB stored each)
#     are uploaded one after another until the disk is full: at least one is
#     stored, the next is refused with a clear error (exit 1, the reason on
#     standard error), and insdiagd does not crash;
#  3. the tmpfs is enlarged: the server's supervisor starts its PostgreSQL
#     again by itself and health says SERVING;
#  4. the runs listed are exactly the acknowledged ones, and each downloads
#     with every one of its samples.
# Skipped (exit 77, ctest's SKIP_RETURN_CODE) where a tmpfs cannot be
# mounted: not root, or a container without the right to mount.
# Usage: tests/server/full_disk_test.sh BUILD_DIR
set -euo pipefail
build_dir=$(cd "${1:?usage: full_disk_test.sh BUILD_DIR}" && pwd)
server=$build_dir/server/insdiagd
cli=$build_dir/clients/insdiag
make_run=$build_dir/tests/tools/make_synthetic_run
disk_mb=160
run_samples=360000

say() { echo "full disk test: $(date +%T) $*"; }
fail() { echo "full disk test: FAILED: $*" >&2; exit 1; }
# shellcheck source=wait_until.sh
source "$(dirname "${BASH_SOURCE[0]}")/wait_until.sh"
skip() { echo "full disk test: SKIPPED: $*"; exit 77; }

[[ $(id -u) -eq 0 ]] || skip "mounting a tmpfs of a fixed size needs root"
work=$(mktemp -d /tmp/insdiag-full-disk.XXXXXX)
chmod 0755 "$work"
disk=$work/disk
mkdir "$disk"
server_pid=
mounted=false
cleanup() {
  local status=$?
  if [[ -n $server_pid ]]; then
    kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null
  fi
  if ((status != 0 && status != 77)) && [[ -f $work/server.log ]]; then
    echo "--- insdiagd's log ---" >&2
    tail -n 40 "$work/server.log" >&2
  fi
  $mounted && umount "$disk"
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
mount -t tmpfs -o "size=${disk_mb}m,mode=0755" tmpfs "$disk" 2>"$work/mount.err" ||
  skip "cannot mount a tmpfs here ($(tail -n 1 "$work/mount.err"))"
mounted=true

grpc_port=$((20000 + RANDOM % 20000))
http_port=$((grpc_port + 1))
"$server" --data-dir "$disk/data" --bind 127.0.0.1 --grpc-port "$grpc_port" --http-port "$http_port" \
  --workers 0 --fleet-refresh-seconds 0 >"$work/server.log" 2>&1 &
server_pid=$!
healthy() { [[ $(curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$http_port/healthz") == 200 ]]; }
wait_until 120 "insdiagd serves" healthy
export INSDIAG_SERVER=127.0.0.1:$grpc_port INSDIAG_TOKEN
INSDIAG_TOKEN=$(cat "$disk/data/admin-token")
say "insdiagd serves on a ${disk_mb} MB tmpfs ($(df -m --output=used "$disk" | tail -n 1 | tr -d ' ') MB used)"

# --- Upload until the disk is full -------------------------------------------
acknowledged=()
refused=false
for seed in 1 2 3 4 5 6; do
  file=$work/run-$seed.csv
  "$make_run" "$file" "$run_samples" 100 "$seed" >/dev/null
  if name=$("$cli" upload "$file" --request-id "full-disk-$$-$seed" 2>"$work/upload.err"); then
    acknowledged+=("$name")
    say "upload $seed stored as $name ($(df -m --output=used "$disk" | tail -n 1 | tr -d ' ') MB used)"
  else
    status=$?
    ((status == 1)) || fail "a refused upload exited $status, not 1: $(cat "$work/upload.err")"
    [[ -s $work/upload.err ]] || fail "upload $seed was refused without a reason"
    say "upload $seed refused: $(tail -n 1 "$work/upload.err")"
    refused=true
    break
  fi
  rm -f "$file"
done
$refused || fail "six uploads of $run_samples samples fitted on a ${disk_mb} MB disk: the test's sizes are wrong"
((${#acknowledged[@]} >= 1)) || fail "not even the first upload was stored on an empty ${disk_mb} MB disk"
kill -0 "$server_pid" 2>/dev/null || fail "insdiagd exited when the disk filled"

# --- Room again: the server recovers by itself -------------------------------
mount -o remount,size=1024m "$disk"
started=$SECONDS
wait_until 120 "healthy again after the disk was enlarged" healthy
# Health can answer before the listing's connection is back: retry it.
listing() { curl -s --fail -H "Authorization: Bearer $INSDIAG_TOKEN" "http://127.0.0.1:$http_port/v1/runs?pageSize=100" >"$work/runs.json"; }
wait_until 60 "listing runs" listing
say "serving again $((SECONDS - started)) s after the disk was enlarged"

# --- Exactly the acknowledged runs, whole --------------------------------------
listed=$(python3 -c 'import json, sys; print(" ".join(sorted(r["name"] for r in json.load(sys.stdin).get("runs", []))))' <"$work/runs.json")
expected=$(printf '%s\n' "${acknowledged[@]}" | sort | tr '\n' ' ' | sed 's/ $//')
[[ $listed == "$expected" ]] || fail "runs listed after the full disk: '$listed'; acknowledged: '$expected'"
for name in "${acknowledged[@]}"; do
  curl -sS --fail -H "Authorization: Bearer $INSDIAG_TOKEN" "http://127.0.0.1:$http_port/v1/$name:download" >"$work/download.csv" ||
    fail "GET /v1/$name:download"
  samples=$(grep -v '^#' "$work/download.csv" | tail -n +2 | grep -c .)
  ((samples == run_samples)) || fail "$name downloads with $samples samples, not $run_samples"
done
say "passed: ${#acknowledged[@]} acknowledged run(s) listed and whole, nothing of the refused upload"
