#!/usr/bin/env bash
# Builds the Debian 12 (bookworm) base image of insdiag's containers from
# Debian's packages, with no image registry: debootstrap a minimal system
# (--variant=minbase), trim it, and `docker import` it as one layer.
#
# The image is cached: it carries the Date of the mirror's bookworm Release
# file (the Debian point release it was made from) in a label, and is made
# again only when that date changes, or with --rebuild. When the mirror does
# not answer, an existing image is kept. Security fixes are not baked in here:
# the images built FROM it (scripts/container-images.sh) upgrade and install
# their packages from bookworm-security at their own build.
#
# Usage: scripts/container-base-image.sh [--rebuild] [--image NAME] [--mirror URL]
# Environment: INSDIAG_DEBIAN_MIRROR (http://deb.debian.org/debian; its
#   debian-security beside it when the URL ends in /debian), INSDIAG_BASE_IMAGE
#   (insdiag-base:bookworm). Needs debootstrap, docker and root (through sudo
#   when not root) to make the image; checking the cached one needs neither.
set -euo pipefail
suite=bookworm
image=${INSDIAG_BASE_IMAGE:-insdiag-base:bookworm}
mirror=${INSDIAG_DEBIAN_MIRROR:-http://deb.debian.org/debian}
rebuild=false
while (($#)); do
  case $1 in
    --rebuild) rebuild=true; shift ;;
    --image) image=$2; shift 2 ;;
    --mirror) mirror=$2; shift 2 ;;
    *) echo "container-base-image.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
say() { echo "insdiag base image: $*" >&2; }

# The snapshot the image would be made from: the suite's Release date.
release_date=$(curl -fsS --max-time 30 "$mirror/dists/$suite/Release" 2>/dev/null | sed -n 's/^Date: //p' | head -n 1) || true
existing=$(docker image inspect -f '{{ index .Config.Labels "org.insdiag.debian-release" }}' "$image" 2>/dev/null) || existing=""
if ! $rebuild && [[ -n $existing ]]; then
  if [[ -z $release_date ]]; then
    say "$mirror does not answer; keeping $image ($existing)"
    exit 0
  fi
  if [[ $existing == "$mirror $suite $release_date" ]]; then
    say "$image is current ($existing)"
    exit 0
  fi
  say "$image was made from '$existing'; the mirror now has $suite of $release_date: making it again"
fi
[[ -n $release_date ]] || { say "cannot read $mirror/dists/$suite/Release"; exit 1; }
command -v debootstrap >/dev/null || { say "debootstrap is missing (scripts/install-deps.sh --containers)"; exit 1; }
if [[ $(id -u) -ne 0 ]]; then
  # debootstrap needs root: the making runs through sudo, as install-deps.sh does.
  say "debootstrap needs root: running through sudo"
  exec sudo INSDIAG_DEBIAN_MIRROR="$mirror" INSDIAG_BASE_IMAGE="$image" "$0" --rebuild
fi

rootfs=$(mktemp -d /tmp/insdiag-base.XXXXXX)
trap 'rm -rf "$rootfs"' EXIT
started=$SECONDS
say "debootstrap --variant=minbase $suite from $mirror ($suite of $release_date)"
debootstrap --variant=minbase "$suite" "$rootfs" "$mirror" >"$rootfs.log" 2>&1 || {
  tail -n 30 "$rootfs.log" >&2; rm -f "$rootfs.log"; exit 1; }
rm -f "$rootfs.log"

# Packages installed later skip documentation, manuals and translations, and
# recommends; apt keeps no downloaded packages.
cat >"$rootfs/etc/dpkg/dpkg.cfg.d/insdiag-slim" <<'EOF'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/info/*
path-exclude /usr/share/locale/*
path-exclude /usr/share/lintian/*
EOF
cat >"$rootfs/etc/apt/apt.conf.d/90insdiag" <<'EOF'
APT::Install-Recommends "false";
APT::Install-Suggests "false";
Acquire::Languages "none";
EOF
cat >"$rootfs/etc/apt/apt.conf.d/docker-clean" <<'EOF'
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
APT::Update::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
Dir::Cache::pkgcache "";
Dir::Cache::srcpkgcache "";
EOF
security_mirror=${mirror%/debian}/debian-security
[[ $mirror == */debian ]] || security_mirror=http://deb.debian.org/debian-security
cat >"$rootfs/etc/apt/sources.list" <<EOF
deb $mirror $suite main
deb $mirror $suite-updates main
deb $security_mirror $suite-security main
EOF
# What debootstrap leaves behind and an image does not need.
find "$rootfs/usr/share/doc" -mindepth 1 -not -name copyright -not -type d -delete
find "$rootfs/usr/share/doc" -mindepth 1 -type d -empty -delete
rm -rf "$rootfs"/usr/share/man/* "$rootfs"/usr/share/info/* "$rootfs"/usr/share/locale/* \
  "$rootfs"/var/cache/apt/*.bin "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/* \
  "$rootfs"/var/log/* "$rootfs"/tmp/* "$rootfs"/etc/machine-id
: >"$rootfs/etc/resolv.conf"
echo insdiag >"$rootfs/etc/hostname"

tar --numeric-owner -C "$rootfs" -c . | docker import \
  --change "LABEL org.insdiag.debian-release=\"$mirror $suite $release_date\"" \
  --change 'ENV LANG=C.UTF-8' \
  --change 'CMD ["/bin/bash"]' \
  - "$image" >/dev/null
say "made $image in $((SECONDS - started)) s ($(docker image inspect -f '{{.Size}}' "$image" | awk '{printf "%.0f MB", $1/1e6}'))"
