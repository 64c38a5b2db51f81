#!/usr/bin/env bash
# One fuzzer's seeds and regression inputs replayed (tests/fuzz/CMakeLists.txt).
# Usage: tests/fuzz/replay.sh REPLAY_BINARY FUZZER TESTS_BUILD
set -euo pipefail
corpus=$(mktemp -d)
trap 'rm -rf "$corpus"' EXIT
"$(dirname "$0")/write_seeds.sh" "$corpus" "$3"
"$1" "$corpus/$2"
