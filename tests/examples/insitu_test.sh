#!/usr/bin/env bash
# The examples/ in-situ program, as a user builds it: install dfbwall into a fresh prefix,
# configure and build examples/insitu against it (find_package(dfbwall) only), run it under
# mpirun with an offscreen 2x2 wall (2 simulating ranks, 4 wall ranks), and check what the
# wall shows: every display's capture of the last frame equals the same program's one-rank
# image cut out (invariant 2 of docs/design.md), 3 ranks render that image byte for byte, and
# it is a picture (many colours), not a blank.
# Then the same on a wall that `dfbwall serve` runs, the simulation connecting to it
# (SessionOptions::connect): the captures again equal the one-rank image.
# Environment: BUILD (the dfbwall build tree), SOURCE, MPIEXEC, COMPARE (compare_captures),
# DFBWALL (the executable, for `dfbwall serve`).
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d /tmp/dfbwall-insitu.XXXXXX)
trap 'rm -rf "$work"' EXIT
layout=$SOURCE/configs/walls/2x2.toml

cmake --install "$BUILD" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/lib/cmake/dfbwall/dfbwallConfig.cmake"
test -f "$work/prefix/include/dfbwall/DataDistributed.h"
# The installed headers hold no test hook.
if grep -rlE 'SessionTesting|TestedSession|friend ' "$work/prefix/include"; then
  echo "FAIL: a test hook in the installed headers"; exit 1
fi
compiler=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
launcher=$(sed -n 's/^CMAKE_CXX_COMPILER_LAUNCHER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
cmake -S "$SOURCE/examples/insitu" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$compiler" \
  ${launcher:+-DCMAKE_CXX_COMPILER_LAUNCHER=$launcher} >/dev/null
cmake --build "$work/build" -j2 >/dev/null
insitu=$work/build/insitu

args=(--grid 40 --blocks 4 --steps 12 --show-every 4 --threads 1)  # 3 frames shown
read -r _ size < <("$COMPARE" --info "$layout")
timeout 120 "$MPIEXEC" -np 6 "$insitu" "${args[@]}" --wall "$layout" --capture "$work/caps"
timeout 120 "$MPIEXEC" -np 1 "$insitu" "${args[@]}" --size "$size" --image "$work/one.png"
timeout 120 "$MPIEXEC" -np 3 "$insitu" "${args[@]}" --size "$size" --image "$work/three.png"

"$COMPARE" "$layout" "$work/caps" "$work/one.png" 3
cmp "$work/one.png" "$work/three.png"

# The same simulation on a wall that is not part of its job (`dfbwall serve`): 2 ranks, all of
# them simulating and rendering, the pieces straight to the wall's 4 processes.
port=$((20000 + ($$ + 7) % 20000))
"$MPIEXEC" -np 4 "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" --offscreen \
  --timeout 20 --capture-root "$work" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
trap 'kill -9 $serve 2>/dev/null || true; rm -rf "$work"' EXIT
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
timeout 120 "$MPIEXEC" -np 2 "$insitu" "${args[@]}" --connect "127.0.0.1:$port" --codec raw \
  --capture "$work/served"
"$COMPARE" "$layout" "$work/served" "$work/one.png" 3
kill -USR1 $serve
wait $serve
colors=$("$COMPARE" --colors "$work/one.png")
echo "the last frame has $colors colours"
if [ "$colors" -lt 500 ]; then echo "FAIL: the image is (nearly) blank"; exit 1; fi
# Bad input through the API: one message naming the cause, a non-zero exit, no hang — also when
# only the wall ranks find the problem (a capture folder they cannot write).
expect_failure() {  # expect_failure TEXT NP ARGS...
  local text=$1 np=$2; shift 2
  local start=$SECONDS status=0
  timeout 60 "$MPIEXEC" -np "$np" "$insitu" "${args[@]}" "$@" >"$work/out" 2>&1 || status=$?
  if [ $status -eq 0 ] || [ $status -eq 124 ] || ! grep -q -- "$text" "$work/out"; then
    echo "FAIL: expected a failure naming '$text' (exit $status):"; cat "$work/out"; exit 1
  fi
  echo "fails as it should in $((SECONDS - start)) s: $(grep -m1 -- "$text" "$work/out")"
}
touch "$work/not-a-folder"
expect_failure "not-a-folder" 6 --wall "$layout" --capture "$work/not-a-folder"
expect_failure "2x2.toml" 3 --wall "$layout"

echo "PASS: the installed package builds the example, and its wall shows the one-rank image"
