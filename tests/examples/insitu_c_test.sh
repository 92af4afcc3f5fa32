#!/usr/bin/env bash
# examples/insitu-c, as a C user builds it: against a fresh install (find_package(dfbwall),
# dfbwall::c), linking one dfbwall library, libdfbwall.so, which exports the C API only. The same
# simulation as examples/insitu renders the one-rank C++ example's image byte for byte on 3
# ranks (on a wall: example_insitu_served). Bad input: one message naming it, a non-zero exit, no
# hang.
# It builds examples/insitu (C++) and examples/insitu-f90 (dfbwall::fortran, when dfbwall has its
# Fortran module) too, each by its own CMakeLists.txt, and leaves the prefix, the three examples
# and the C++ one-rank image in $BUILD/examples-installed for example_insitu_installed,
# example_insitu_f90 and example_insitu_served (CTest fixture insitu_installed).
# Environment: BUILD (the dfbwall build tree), SOURCE, MPIEXEC, COMPARE (compare_captures),
# FORTRAN (1: dfbwall was built with its Fortran module).
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$BUILD/examples-installed
rm -rf "$work"
mkdir -p "$work"
trap 'rm -rf "$work/out"' EXIT
layout=$SOURCE/configs/walls/2x2.toml
start=$SECONDS

cmake --install "$BUILD" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/dfbwall/dfbwall.h"
test -f "$work/prefix/include/dfbwall/DataDistributed.h"
test -f "$work/prefix/lib/cmake/dfbwall/dfbwallConfig.cmake"
# The installed headers hold no test hook.
if grep -rlE 'SessionTesting|TestedSession|friend ' "$work/prefix/include"; then
  echo "FAIL: a test hook in the installed headers"; exit 1
fi
lib=$(ls "$work"/prefix/lib/libdfbwall.so.*.* | head -1)
# libdfbwall.so alone answers -ldfbwall: a libdfbwall.a beside it (the C++ API) would be taken by
# a static link or by CMake's -l form in a system folder, without the C API in it.
if [ -e "$work/prefix/lib/libdfbwall.a" ]; then echo "FAIL: a libdfbwall.a beside libdfbwall.so"; exit 1; fi
# The shared library exports the C API and nothing else.
if others=$(nm -D --defined-only "$lib" | awk '{print $3}' | grep -v '^dfbwall_'); then
  echo "FAIL: libdfbwall.so exports more than dfbwall_*:"; echo "$others" | head; exit 1
fi
# The three examples' own CMakeLists.txt, configured together (tests/examples/installed).
cmake_var() { sed -n "s/^$1:[A-Z]*=//p" "$BUILD/CMakeCache.txt"; }
fortran=""
if [ "${FORTRAN:-0}" = 1 ]; then
  test -f "$work/prefix/include/dfbwall/fortran/dfbwall.mod"
  fortran=$(cmake_var CMAKE_Fortran_COMPILER)
fi
launcher=$(cmake_var CMAKE_CXX_COMPILER_LAUNCHER)
cmake -S "$SOURCE/tests/examples/installed" -B "$work/build" -DEXAMPLES="$SOURCE/examples" \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER="$(cmake_var CMAKE_C_COMPILER)" \
  -DCMAKE_CXX_COMPILER="$(cmake_var CMAKE_CXX_COMPILER)" \
  ${fortran:+-DWITH_FORTRAN=ON -DCMAKE_Fortran_COMPILER=$fortran} \
  ${launcher:+-DCMAKE_C_COMPILER_LAUNCHER=$launcher -DCMAKE_CXX_COMPILER_LAUNCHER=$launcher} \
  >/dev/null
cmake --build "$work/build" -j2 >/dev/null
c=$work/build/insitu-c/insitu-c
# One dfbwall library in the C program's link; Embree, TBB and the rest come with it.
needed=$(readelf -d "$c" | sed -n 's/.*NEEDED.*\[\(.*\)\]/\1/p' | tr '\n' ' ')
echo "insitu-c needs: $needed"
if ! grep -q 'libdfbwall.so' <<<"$needed" || grep -qE 'embree|tbb|zmq' <<<"$needed"; then
  echo "FAIL: insitu-c should link libdfbwall.so and MPI, not the C++ dependencies"; exit 1
fi

args=(--grid 40 --blocks 4 --steps 12 --show-every 4 --threads 1)  # 3 frames shown
read -r _ size < <("$COMPARE" --info "$layout")
timeout 120 "$MPIEXEC" -np 1 "$work/build/insitu/insitu" "${args[@]}" --size "$size" \
  --image "$work/cpp.png" >/dev/null
timeout 120 "$MPIEXEC" -np 3 "$c" "${args[@]}" --size "$size" --image "$work/c3.png"
cmp "$work/cpp.png" "$work/c3.png"

expect_failure() {  # expect_failure TEXT NP ARGS...
  local text=$1 np=$2; shift 2
  local began=$SECONDS status=0
  timeout 60 "$MPIEXEC" -np "$np" "$c" "${args[@]}" "$@" >"$work/out" 2>&1 || status=$?
  if [ $status -eq 0 ] || [ $status -eq 124 ] || ! grep -q -- "$text" "$work/out"; then
    echo "FAIL: expected a failure naming '$text' (exit $status):"; cat "$work/out"; exit 1
  fi
  echo "fails as it should in $((SECONDS - began)) s: $(grep -m1 -- "$text" "$work/out")"
}
expect_failure "2x2.toml" 3 --wall "$layout"

echo "PASS in $((SECONDS - start)) s: the C example renders the C++ example's image, on 3 ranks"
