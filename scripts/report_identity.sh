#!/usr/bin/env bash
# Checks that a change leaves insdiag's reports byte-for-byte unchanged: the
# scenario runs are simulated with fixed seeds and analysed by a base build
# and by the current build, and every file each writes is compared.
#
# Usage: scripts/report_identity.sh [--base-commit REV | --base-cli PATH] [--cli PATH] [--work DIR] [--keep]
#   --base-commit REV  build `insdiag` at REV (default: main) in a detached
#                      worktree, .cache/report-identity-base (kept between
#                      calls, so only what changed since is rebuilt)
#   --base-cli PATH    use this already built base `insdiag` instead
#   --cli PATH         the current build's `insdiag` (default: build/clients/insdiag)
#   --work DIR         where the runs and reports go (default: a new temporary directory)
#   --keep             keep the work directory (it is kept anyway when they differ)
#
# The scenarios (each a `simulate` and one or more `analyze` calls):
#   static     one hour level and still, seed 11
#   positions  the multi-position profile with a hidden gyro z scale factor, seed 12; analysed with --add
#   rotations  with a gyro x bias step at 1500 s, seed 13
#   full       two hours of every excitation with an accelerometer scale factor, seed 14; --discover
# Both builds analyse the base build's runs, so a difference in the analysis
# is told apart from one in the simulator (whose runs are compared as well).
#
# Exit status: 0 when every file is identical, 1 when one differs (the diff of
# the first lines is printed), 2 for bad usage or a failed build or run.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
base_commit=main
base_cli=
cli=$root/build/clients/insdiag
work=
keep=false
while (($#)); do
  case $1 in
    --base-commit) base_commit=$2; shift 2 ;;
    --base-cli) base_cli=$2; shift 2 ;;
    --cli) cli=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --keep) keep=true; shift ;;
    -h | --help) sed -n '2,24p' "$0"; exit 0 ;;
    *) echo "report_identity.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[[ -x $cli ]] || { echo "report_identity.sh: no current build at $cli (build first, or --cli)" >&2; exit 2; }
if [[ -z $work ]]; then work=$(mktemp -d /tmp/insdiag-report-identity.XXXXXX); fi
mkdir -p "$work"

# The base build: a detached worktree at the commit, the CLI target only.
if [[ -z $base_cli ]]; then
  rev=$(git -C "$root" rev-parse --verify "$base_commit^{commit}") ||
    { echo "report_identity.sh: no commit '$base_commit'" >&2; exit 2; }
  tree=$root/.cache/report-identity-base
  mkdir -p "$root/.cache"
  if [[ ! -d $tree ]]; then git -C "$root" worktree add --detach "$tree" "$rev" >/dev/null; fi
  git -C "$tree" checkout --detach -q "$rev"
  export CCACHE_DIR=${CCACHE_DIR:-$root/.cache/ccache} CCACHE_BASEDIR=$tree
  echo "report_identity.sh: building the base insdiag at ${rev:0:12} in $tree/build" >&2
  # The current build's options, so that ccache serves every file the change left alone.
  werror=OFF
  if grep -q '^INSDIAG_WARNINGS_AS_ERRORS:BOOL=ON' "$(dirname "$(dirname "$cli")")/CMakeCache.txt" 2>/dev/null; then werror=ON; fi
  cmake -S "$tree" -B "$tree/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DINSDIAG_WARNINGS_AS_ERRORS=$werror \
    >"$work/base-configure.log" 2>&1 ||
    { echo "report_identity.sh: configuring the base failed: $work/base-configure.log" >&2; exit 2; }
  nice cmake --build "$tree/build" -j2 --target insdiag >"$work/base-build.log" 2>&1 ||
    { echo "report_identity.sh: building the base failed: $work/base-build.log" >&2; exit 2; }
  base_cli=$tree/build/clients/insdiag
fi
[[ -x $base_cli ]] || { echo "report_identity.sh: no base build at $base_cli" >&2; exit 2; }

# name|profile|seed|simulate options|analyze option sets separated by ';'
scenarios=(
  "static|static|11||--json"
  "positions|positions|12|--effect gyro_scale_factor.z=2.5e-4|--json;--add gyro_scale_factor.z"
  "rotations|rotations|13|--bias-step gyro.x=1500,3e-6|--json"
  "full|full|14|--effect acc_scale_factor.x=3e-4|--json;--discover"
)

run_cli() {  # run_cli BINARY OUT_PREFIX ARGS... : stdout, stderr and status into files
  local binary=$1 prefix=$2
  shift 2
  local status=0
  "$binary" "$@" >"$prefix.out" 2>"$prefix.err" || status=$?
  echo "$status" >"$prefix.status"
}

mkdir -p "$work/base" "$work/current"
for scenario in "${scenarios[@]}"; do
  IFS='|' read -r name profile seed sim_options analyze_sets <<<"$scenario"
  echo "report_identity.sh: $name (profile $profile, seed $seed)" >&2
  for side in base current; do
    binary=$base_cli
    [[ $side == current ]] && binary=$cli
    # shellcheck disable=SC2086  # the options are words
    run_cli "$binary" "$work/$side/$name.simulate" simulate --profile "$profile" --rate 10 --seed "$seed" \
      $sim_options "$work/$side/$name.csv"
    [[ $(cat "$work/$side/$name.simulate.status") == 0 ]] ||
      { echo "report_identity.sh: $side simulate of $name failed: $work/$side/$name.simulate.err" >&2; exit 2; }
  done
  run=$work/base/$name.csv
  IFS=';' read -r -a sets <<<"$analyze_sets"
  for i in "${!sets[@]}"; do
    for side in base current; do
      binary=$base_cli
      [[ $side == current ]] && binary=$cli
      series=$work/$side/$name.analyze$i.series.csv
      # shellcheck disable=SC2086
      run_cli "$binary" "$work/$side/$name.analyze$i" analyze "$run" ${sets[$i]} --series "$series"
    done
  done
done

# The simulate lines name the output file, whose directory differs by side.
for f in "$work"/base/*.simulate.out "$work"/current/*.simulate.out; do
  sed -i "s|$work/[a-z]*/||" "$f"
done

differ=0
compared=0
for f in "$work"/base/*; do
  [[ -f $f ]] || continue
  rel=${f#"$work"/base/}
  compared=$((compared + 1))
  if ! cmp -s "$f" "$work/current/$rel"; then
    differ=$((differ + 1))
    echo "report_identity.sh: DIFFERS: $rel" >&2
    diff "$f" "$work/current/$rel" | head -n 20 >&2 || true
  fi
done
if ((differ)); then
  echo "report_identity.sh: $differ of $compared files differ (kept in $work)" >&2
  exit 1
fi
echo "report_identity.sh: all $compared files byte-for-byte identical ($work)"
$keep || rm -rf "$work"
