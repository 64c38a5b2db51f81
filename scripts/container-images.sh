#!/usr/bin/env bash
# Builds insdiag's container images, no image registry needed:
#   insdiag-base:bookworm   Debian 12 from Debian's packages (scripts/container-base-image.sh; cached)
#   insdiag-postgres:15     PostgreSQL 15 from Debian's packages (docker/postgres.Dockerfile)
#   insdiag:local           insdiagd and the insdiag CLI of this machine's build (docker/insdiagd.Dockerfile)
# The runtime image copies the already built binaries (scripts/build.sh, on
# Debian 12: the image's libraries are Debian 12's) and installs only the
# Debian packages of the shared libraries they load, found here with ldd and
# dpkg. docker-compose.yml runs the two last images.
#
# Usage: scripts/container-images.sh [--build-dir DIR] [--rebuild-base]
# Environment: INSDIAG_BUILD_DIR (<checkout>/build), INSDIAG_BASE_IMAGE,
#   INSDIAG_IMAGE (insdiag:local), INSDIAG_POSTGRES_IMAGE (insdiag-postgres:15),
#   INSDIAG_DEBIAN_MIRROR (see scripts/container-base-image.sh).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir=${INSDIAG_BUILD_DIR:-$root/build}
base_image=${INSDIAG_BASE_IMAGE:-insdiag-base:bookworm}
image=${INSDIAG_IMAGE:-insdiag:local}
postgres_image=${INSDIAG_POSTGRES_IMAGE:-insdiag-postgres:15}
base_args=()
while (($#)); do
  case $1 in
    --build-dir) build_dir=$2; shift 2 ;;
    --rebuild-base) base_args+=(--rebuild); shift ;;
    *) echo "container-images.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
say() { echo "insdiag images: $*" >&2; }
server=$build_dir/server/insdiagd
cli=$build_dir/clients/insdiag
for binary in "$server" "$cli"; do
  [[ -x $binary ]] || { say "no $binary: build first (scripts/build.sh)"; exit 1; }
done
# Without the buildx plugin, the classic builder (it needs no plugin).
if [[ -z ${DOCKER_BUILDKIT:-} ]] && ! docker buildx version >/dev/null 2>&1; then
  export DOCKER_BUILDKIT=0
fi
# The build's RUN steps fetch Debian's packages; the daemon may have no
# bridge network, so they use the host's.
build() { docker build --network host --build-arg BASE_IMAGE="$base_image" "$@"; }
quiet_build() {
  local log
  log=$(mktemp)
  if ! build "$@" >"$log" 2>&1; then tail -n 40 "$log" >&2; rm -f "$log"; return 1; fi
  rm -f "$log"
}

"$root/scripts/container-base-image.sh" --image "$base_image" "${base_args[@]}"

started=$SECONDS
quiet_build -t "$postgres_image" -f "$root/docker/postgres.Dockerfile" "$root/docker"
say "$postgres_image ready in $((SECONDS - started)) s"

# The Debian packages of every shared library the binaries load. dpkg names
# a file by the path it was unpacked to: /lib/… or /usr/lib/… (merged /usr),
# and a library reached through an alternative by its target.
mapfile -t libraries < <(ldd "$server" "$cli" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u)
candidates=()
for library in "${libraries[@]}"; do
  for path in "$library" "$(readlink -f "$library")"; do
    candidates+=("$path" "/usr${path#/usr}" "${path#/usr}")
  done
done
owners=$(dpkg-query -S "${candidates[@]}" 2>/dev/null || true)
packages=()
for library in "${libraries[@]}"; do
  owner=""
  for path in "$library" "$(readlink -f "$library")"; do
    for candidate in "$path" "/usr${path#/usr}" "${path#/usr}"; do
      owner=$(awk -v f="$candidate" '{ p = $0; sub(/^[^:]*(:[a-z0-9]+)?: /, "", p) } p == f { sub(/[:,].*/, "", $1); print $1; exit }' <<<"$owners")
      [[ -n $owner ]] && break 2
    done
  done
  [[ -n $owner ]] || { say "no Debian package owns $library (ldd of $server, $cli)"; exit 1; }
  packages+=("$owner")
done
mapfile -t packages < <(printf '%s\n' "${packages[@]}" | sort -u)
say "runtime packages: ${packages[*]}"

context=$(mktemp -d /tmp/insdiag-image.XXXXXX)
trap 'rm -rf "$context"' EXIT
cp "$server" "$cli" "$root/docker/insdiag-healthz" "$context/"
if [[ -d $build_dir/web ]]; then
  cp -rL "$build_dir/web" "$context/web"
else
  say "no page in $build_dir/web: the image serves the REST API only"
  mkdir "$context/web"
fi
cp "$root/docker/insdiagd.Dockerfile" "$context/Dockerfile"
started=$SECONDS
previous=$(docker image inspect -f '{{.Id}}' "$image" 2>/dev/null) || previous=""
quiet_build -t "$image" --build-arg RUNTIME_PACKAGES="${packages[*]}" "$context"
# The image of the previous binaries, now untagged, goes (unless a container uses it).
if [[ -n $previous && $previous != "$(docker image inspect -f '{{.Id}}' "$image")" &&
      -z $(docker image inspect -f '{{join .RepoTags " "}}' "$previous" 2>/dev/null) ]]; then
  docker rmi "$previous" >/dev/null 2>&1 || true
fi
say "$image ready in $((SECONDS - started)) s ($(docker image inspect -f '{{.Size}}' "$image" | awk '{printf "%.0f MB", $1/1e6}'))"
