# Sourced by the server's shell tests: poll a condition instead of sleeping a
# fixed time. The caller defines `fail` and may set `server_pid`, the insdiagd
# whose exit ends the wait early (a server that died will not become ready).

wait_until() {  # SECONDS WHAT COMMAND...
  local seconds=$1 what=$2
  shift 2
  for ((i = 0; i < seconds * 10; i++)); do
    "$@" && return 0
    if [[ -n "${server_pid:-}" ]] && ! kill -0 "$server_pid" 2>/dev/null; then
      fail "insdiagd exited while waiting until $what"
    fi
    sleep 0.1
  done
  fail "not $what after $seconds s"
}
