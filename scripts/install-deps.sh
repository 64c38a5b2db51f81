#!/usr/bin/env bash
# Installs the Debian packages insdiag builds, tests and runs with, when missing,
# and the page's npm packages (clients/web, from its package-lock.json).
# Usage: scripts/install-deps.sh [--browser] [--containers]
#   --browser     adds chromium for the page's end-to-end tests
#   --containers  adds what the container images and the `container` test
#                 need: Debian's docker.io (engine and client), docker-compose
#                 and debootstrap. The engine (dockerd) is not started here:
#                 without a running engine the `container` test skips.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config ccache
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler grpc-proto
  libeigen3-dev libceres-dev libabsl-dev
  libpq-dev postgresql libssl-dev openssl curl
  clang libclang-rt-14-dev
  libgtest-dev libgmock-dev libbenchmark-dev poppler-utils
  libcpp-httplib-dev libcli11-dev
  python3-grpcio python3-grpc-tools python3-numpy python3-scipy
  nodejs npm
)
containers=false
for option in "$@"; do
  case $option in
    --browser) packages+=(chromium) ;;
    --containers) containers=true; packages+=(docker.io docker-compose debootstrap) ;;
    *) echo "install-deps.sh: unknown option '$option'" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
# nodejs/npm may come from outside Debian's packages on some images; accept them on PATH.
if [[ " ${missing[*]} " == *" nodejs "* ]] && command -v node >/dev/null; then missing=("${missing[@]/nodejs}"); fi
if [[ " ${missing[*]} " == *" npm "* ]] && command -v npm >/dev/null; then missing=("${missing[@]/npm}"); fi
# A Docker engine from elsewhere (docker-ce, the compose plugin) conflicts with
# Debian's docker.io: accept it. A docker client alone is no engine: without
# dockerd, docker.io is installed (it brings its own client).
if $containers && command -v dockerd >/dev/null; then
  missing=("${missing[@]/docker.io}")
  if docker compose version >/dev/null 2>&1 || command -v docker-compose >/dev/null; then missing=("${missing[@]/docker-compose}"); fi
fi
read -r -a missing <<<"${missing[*]}"

if ((${#missing[@]})); then
  echo "insdiag: installing ${missing[*]}" >&2
  sudo_cmd=()
  [[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

"$(dirname "$0")/install-web-deps.sh"
