#!/usr/bin/env bash
# examples/insitu-c, as a C user builds it: against a fresh install (find_package(dfbwall),
# dfbwall::c), linking one dfbwall library, libdfbwall.so, which exports the C API only. The same
# simulation as examples/insitu renders the one-rank C++ example's image byte for byte on 3
# ranks, and on the offscreen 2x2 wall (its own 4 wall ranks) every display's capture equals that
# image cut out. Bad input: one message naming it, a non-zero exit, no hang.
# It also builds examples/insitu-f90 (dfbwall::fortran) when dfbwall has its Fortran module, and
# leaves the prefix, the three examples and the C++ image in $BUILD/examples-installed for
# example_insitu_f90 and example_insitu_served (CTest fixture insitu_installed).
# Environment: BUILD (the dfbwall build tree), SOURCE, MPIEXEC, COMPARE (compare_captures),
# FORTRAN (1: dfbwall was built with its Fortran module).
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$BUILD/examples-installed
rm -rf "$work"
mkdir -p "$work"
trap 'rm -rf "$work/caps" "$work/out"' EXIT
layout=$SOURCE/configs/walls/2x2.toml
start=$SECONDS

cmake --install "$BUILD" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/dfbwall/dfbwall.h"
lib=$(ls "$work"/prefix/lib/libdfbwall.so.*.* | head -1)
# libdfbwall.so alone answers -ldfbwall: a libdfbwall.a beside it (the C++ API) would be taken by
# a static link or by CMake's -l form in a system folder, without the C API in it.
if [ -e "$work/prefix/lib/libdfbwall.a" ]; then echo "FAIL: a libdfbwall.a beside libdfbwall.so"; exit 1; fi
# The shared library exports the C API and nothing else.
if others=$(nm -D --defined-only "$lib" | awk '{print $3}' | grep -v '^dfbwall_'); then
  echo "FAIL: libdfbwall.so exports more than dfbwall_*:"; echo "$others" | head; exit 1
fi
build() {  # build EXAMPLE: configure and build examples/EXAMPLE against the prefix
  local c cxx fortran launcher
  c=$(sed -n 's/^CMAKE_C_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
  cxx=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
  fortran=$(sed -n 's/^CMAKE_Fortran_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
  launcher=$(sed -n 's/^CMAKE_CXX_COMPILER_LAUNCHER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
  cmake -S "$SOURCE/examples/$1" -B "$work/build-$1" -DCMAKE_PREFIX_PATH="$work/prefix" \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER="$c" -DCMAKE_CXX_COMPILER="$cxx" \
    ${fortran:+-DCMAKE_Fortran_COMPILER=$fortran} \
    ${launcher:+-DCMAKE_C_COMPILER_LAUNCHER=$launcher -DCMAKE_CXX_COMPILER_LAUNCHER=$launcher} \
    >/dev/null
  cmake --build "$work/build-$1" -j2 >/dev/null
}
build insitu
build insitu-c
c=$work/build-insitu-c/insitu-c
if [ "${FORTRAN:-0}" = 1 ]; then
  test -f "$work/prefix/include/dfbwall/fortran/dfbwall.mod"
  build insitu-f90
fi
# One dfbwall library in the C program's link; Embree, TBB and the rest come with it.
needed=$(readelf -d "$c" | sed -n 's/.*NEEDED.*\[\(.*\)\]/\1/p' | tr '\n' ' ')
echo "insitu-c needs: $needed"
if ! grep -q 'libdfbwall.so' <<<"$needed" || grep -qE 'embree|tbb|zmq' <<<"$needed"; then
  echo "FAIL: insitu-c should link libdfbwall.so and MPI, not the C++ dependencies"; exit 1
fi

args=(--grid 40 --blocks 4 --steps 12 --show-every 4 --threads 1)  # 3 frames shown
read -r _ size < <("$COMPARE" --info "$layout")
timeout 120 "$MPIEXEC" -np 1 "$work/build-insitu/insitu" "${args[@]}" --size "$size" \
  --image "$work/cpp.png" >/dev/null
timeout 120 "$MPIEXEC" -np 3 "$c" "${args[@]}" --size "$size" --image "$work/c3.png"
cmp "$work/cpp.png" "$work/c3.png"
timeout 120 "$MPIEXEC" -np 6 "$c" "${args[@]}" --wall "$layout" --capture "$work/caps" >/dev/null
"$COMPARE" "$layout" "$work/caps" "$work/cpp.png" 3

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

echo "PASS in $((SECONDS - start)) s: the C example renders the C++ example's image, on 3 ranks and on the wall"
