#!/usr/bin/env bash
# examples/insitu-f90 and the Fortran module, as example_insitu_c_installed installed and built
# them (fixture insitu_installed, $BUILD/examples-installed): the same simulation as
# examples/insitu renders the one-rank C++ example's image byte for byte on 1 and 3 ranks (on a
# wall: example_insitu_served). Bad input: the C API's message on every rank, a non-zero exit, no hang. Then
# tests/examples/fortran_errors.f90, built with plain mpif90 against the prefix, checks the
# module's statuses, messages and array kinds on 3 ranks.
# Environment: BUILD, SOURCE, MPIEXEC, COMPARE (compare_captures).
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
installed=$BUILD/examples-installed
f90=$installed/build/insitu-f90/insitu-f90
work=$(mktemp -d /tmp/dfbwall-insitu-f90.XXXXXX)
trap 'rm -rf "$work"' EXIT
layout=$SOURCE/configs/walls/2x2.toml
start=$SECONDS
[ -x "$f90" ] || { echo "FAIL: no $f90: run example_insitu_c_installed first"; exit 1; }

args=(--grid 40 --blocks 4 --steps 12 --show-every 4 --threads 1)  # 3 frames, as the fixture's
read -r _ size < <("$COMPARE" --info "$layout")
timeout 120 "$MPIEXEC" -np 1 "$f90" "${args[@]}" --size "$size" --image "$work/f1.png" >/dev/null
cmp "$installed/cpp.png" "$work/f1.png"
timeout 120 "$MPIEXEC" -np 3 "$f90" "${args[@]}" --size "$size" --image "$work/f3.png"
cmp "$installed/cpp.png" "$work/f3.png"
echo "the Fortran example renders the C++ example's image, on 1 and 3 ranks"

expect_failure() {  # expect_failure TEXT RANKS NP ARGS...: TEXT said by RANKS of the NP ranks
  local text=$1 ranks=$2 np=$3; shift 3
  local began=$SECONDS status=0 said
  timeout 60 "$MPIEXEC" -np "$np" "$f90" "${args[@]}" "$@" >"$work/out" 2>&1 || status=$?
  said=$(grep -c -- "$text" "$work/out" || true)
  if [ $status -eq 0 ] || [ $status -eq 124 ] || [ "$said" -lt "$ranks" ]; then
    echo "FAIL: expected a failure naming '$text' on $ranks ranks (exit $status):"
    cat "$work/out"; exit 1
  fi
  echo "fails as it should in $((SECONDS - began)) s, $said times: $(grep -m1 -- "$text" "$work/out")"
}
# Without a status argument a failing call stops every rank with the C API's message.
expect_failure "2x2.toml" 3 3 --wall "$layout"
expect_failure "unknown option" 1 1 --colour red

# The module's statuses, messages and array kinds, built as a plain mpif90 user would.
fortran=$(sed -n 's/^CMAKE_Fortran_COMPILER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
sanitize=$(sed -n 's/^DFBWALL_SANITIZE:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
OMPI_FC=$fortran mpif90 -std=f2018 -Wall -I"$installed/prefix/include/dfbwall/fortran" \
  "$SOURCE/tests/examples/fortran_errors.f90" -o "$work/fortran-errors" \
  -L"$installed/prefix/lib" -ldfbwall_fortran -ldfbwall -Wl,-rpath,"$installed/prefix/lib" \
  ${sanitize:+-fsanitize=$sanitize}
timeout 60 "$MPIEXEC" -np 3 "$work/fortran-errors" >"$work/out" 2>&1 || {
  echo "FAIL: fortran_errors.f90:"; cat "$work/out"; exit 1; }
[ "$(grep -c 'as they should be' "$work/out")" = 3 ] || { cat "$work/out"; exit 1; }
echo "the Fortran module's statuses, messages and voxel kinds are right on 3 ranks"
echo "PASS in $((SECONDS - start)) s"
