#!/usr/bin/env bash
# The examples/ in-situ program, as a user builds it against an installed dfbwall
# (find_package(dfbwall) only; example_insitu_c_installed installs and builds it: fixture
# insitu_installed, $BUILD/examples-installed): under mpirun with an offscreen 2x2 wall (2
# simulating ranks, 4 wall ranks) every display's capture of the last frame equals the same
# program's one-rank image cut out (invariant 2 of docs/design.md), 3 ranks render that image
# byte for byte, and it is a picture (many colours), not a blank. Bad input: one message naming
# it, a non-zero exit, no hang, also when only the wall ranks find the problem. (The same program
# on a wall that `dfbwall serve` runs: example_insitu_served.)
# Environment: BUILD (the dfbwall build tree), SOURCE, MPIEXEC, COMPARE (compare_captures).
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
installed=$BUILD/examples-installed
insitu=$installed/build/insitu/insitu
work=$(mktemp -d /tmp/dfbwall-insitu.XXXXXX)
trap 'rm -rf "$work"' EXIT
layout=$SOURCE/configs/walls/2x2.toml
start=$SECONDS
[ -x "$insitu" ] || { echo "FAIL: no $insitu: run example_insitu_c_installed first"; exit 1; }

args=(--grid 40 --blocks 4 --steps 12 --show-every 4 --threads 1)  # 3 frames, as the fixture's
read -r _ size < <("$COMPARE" --info "$layout")
timeout 120 "$MPIEXEC" -np 6 "$insitu" "${args[@]}" --wall "$layout" --capture "$work/caps"
timeout 120 "$MPIEXEC" -np 3 "$insitu" "${args[@]}" --size "$size" --image "$work/three.png"
"$COMPARE" "$layout" "$work/caps" "$installed/cpp.png" 3
cmp "$installed/cpp.png" "$work/three.png"
colors=$("$COMPARE" --colors "$installed/cpp.png")
echo "the last frame has $colors colours"
if [ "$colors" -lt 500 ]; then echo "FAIL: the image is (nearly) blank"; exit 1; fi

expect_failure() {  # expect_failure TEXT NP ARGS...
  local text=$1 np=$2; shift 2
  local began=$SECONDS status=0
  timeout 60 "$MPIEXEC" -np "$np" "$insitu" "${args[@]}" "$@" >"$work/out" 2>&1 || status=$?
  if [ $status -eq 0 ] || [ $status -eq 124 ] || ! grep -q -- "$text" "$work/out"; then
    echo "FAIL: expected a failure naming '$text' (exit $status):"; cat "$work/out"; exit 1
  fi
  echo "fails as it should in $((SECONDS - began)) s: $(grep -m1 -- "$text" "$work/out")"
}
touch "$work/not-a-folder"
expect_failure "not-a-folder" 6 --wall "$layout" --capture "$work/not-a-folder"
expect_failure "2x2.toml" 3 --wall "$layout"

echo "PASS in $((SECONDS - start)) s: the installed package's example on its own wall shows the one-rank image"
