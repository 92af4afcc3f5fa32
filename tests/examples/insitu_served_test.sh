#!/usr/bin/env bash
# The in-situ examples in C++, C, Fortran and Python on one served wall: `dfbwall serve` runs the
# offscreen 2x2 wall with a token file; each example in turn connects (--connect, --token-file),
# 2 ranks simulating and rendering, and the wall's captures of its last frame equal the one-rank
# C++ example's image cut out, byte for byte (issue 38, "Done when"). A job without the token is
# refused, and the wall then still takes the next good one.
# Uses what example_insitu_c_installed leaves in $BUILD/examples-installed (fixture
# insitu_installed): the prefix, the examples built against it, and the C++ image (cpp.png).
# Environment: BUILD, SOURCE, MPIEXEC, COMPARE, DFBWALL; PYTHON (empty: no Python part, as in a
# sanitized build, docs/insitu.md "Known limits").
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
installed=$BUILD/examples-installed
work=$(mktemp -d /tmp/dfbwall-insitu-served.XXXXXX)
logs="serve.out serve.err job.out"
source "$SOURCE/tests/apps/service_jobs_lib.sh"
layout=$SOURCE/configs/walls/2x2.toml
start=$SECONDS
test -f "$installed/cpp.png" || fail "no $installed/cpp.png: run example_insitu_c_installed first"

run=("$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1)
"${run[@]}" -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen 127.0.0.1:0 \
  --offscreen --timeout 20 --capture-root "$work" --token-file "$work/token" \
  >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
for _ in $(seq 200); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
port=$(sed -n 's/^dfbwall: wall service on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve.out")
[ -n "$port" ] || fail "serve did not start"
if grep -q "$(cat "$work/token")" "$work/serve.out" "$work/serve.err"; then
  fail "serve printed its token"
fi

args=(--grid 40 --blocks 4 --steps 12 --show-every 4 --threads 1)  # 3 frames, as the fixture's
shown=0
# show NAME COMMAND...: the example connects, its captures equal the C++ image.
show() {
  local name=$1 began=$SECONDS; shift
  timeout 120 "$@" "${args[@]}" --connect "127.0.0.1:$port" --token-file "$work/token" \
    --capture "$work/$name" >"$work/job.out" 2>&1 || fail "the $name example on the served wall"
  "$COMPARE" "$layout" "$work/$name" "$installed/cpp.png" 3 >>"$work/job.out" 2>&1 ||
    fail "the served wall's captures of the $name example"
  echo "$name: the served wall shows the C++ image ($((SECONDS - began)) s)"
  shown=$((shown + 1))
}
show c++ "${run[@]}" -np 2 "$installed/build/insitu/insitu" --codec raw
show c "${run[@]}" -np 2 "$installed/build/insitu-c/insitu-c"
# A job with another token is refused with a message, and does not hang.
echo "not-the-token" >"$work/other-token"
chmod 600 "$work/other-token"
status=0
timeout 60 "${run[@]}" -np 1 "$installed/build/insitu-c/insitu-c" "${args[@]}" \
  --connect "127.0.0.1:$port" --token-file "$work/other-token" >"$work/job.out" 2>&1 || status=$?
if [ $status -eq 0 ] || [ $status -eq 124 ]; then fail "a job with a wrong token (exit $status)"; fi
echo "a wrong token: refused (exit $status): $(grep -m1 -i 'token\|refused\|denied' "$work/job.out" || head -1 "$work/job.out")"
if [ -x "$installed/build/insitu-f90/insitu-f90" ]; then
  show fortran "${run[@]}" -np 2 "$installed/build/insitu-f90/insitu-f90"
fi
if [ -n "${PYTHON:-}" ]; then
  site=$(ls -d "$installed"/prefix/lib*/python3*/site-packages)
  show python env PYTHONPATH="$site" "${run[@]}" -x PYTHONPATH -np 2 "$PYTHON" \
    "$SOURCE/examples/insitu.py"
fi
kill -USR1 "$serve"
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""
echo "PASS in $((SECONDS - start)) s: $shown examples on one served wall"
