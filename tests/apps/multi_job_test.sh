#!/usr/bin/env bash
# Several jobs on one wall at once, each in its window (docs/service.md, "Several jobs at once").
#   multi_job_test.sh LAYOUT [composite|glfw]   (the 2x2 wall; composite: only the composite
#       part, offscreen; glfw: only the composite part, in GLFW windows under Xvfb, captures read
#       from the X server)
# One `dfbwall serve --max-jobs 2 --background "#000000"`; two jobs of the pattern renderer in
# overlapping windows across display borders, running at the same time:
#  - each job's captures (its window's part of each display) equal the one-process render of its
#    window, byte for byte, though the other job's window covers part of it on the displays;
#  - a third job is refused busy while both run;
#  - kill -9 of a rank of one job: the other keeps presenting new frames (well within the
#    timeout that would end the dead one) and ends as usual.
# The composite: a `serve --capture` wall (default --max-jobs) with two jobs of the primary
# renderer (the same frame every frame; one raw, one snappy) in the same windows: some capture of
# every display equals the background with both one-process renders at their windows, the newer
# on top, byte for byte.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
if [ "${2:-}" = glfw ] && [ -z "${MULTI_JOB_TEST_INNER:-}" ]; then
  # A server number of its own, so a concurrent Xvfb test elsewhere cannot take the same one.
  exec xvfb-run -a -n $((300 + RANDOM % 500)) -s "-screen 0 1280x1024x24 -noreset" \
    env MULTI_JOB_TEST_INNER=1 "$0" "$@"
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
logs="serve.out serve.err a.out b.out c.out serve2.out serve2.err a2.out b2.out"
source "$(dirname "$0")/service_jobs_lib.sh"

layout=$1
port=""  # serve listens on port 0; the port it took is read from its first line
window_a=90,70,250,170 window_b=20,20,200,150

# composite [SERVE OPTIONS...]: the wall's own captures of two jobs at once equal the composite.
composite() {
  local port2="" ca=$work/jobs/composite-a cb=$work/jobs/composite-b
  mkdir -p "$work/jobs"  # the jobs' capture root; the wall's own captures outside it
  local x=()
  [ -z "${DISPLAY:-}" ] || x=(-x DISPLAY -x XAUTHORITY)
  "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "${x[@]}" \
    -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen 127.0.0.1:0 \
    --timeout "$timeout" --capture-root "$work/jobs" --background "#000000" --capture "$work/wall" \
    --capture-every 3 "$@" >"$work/serve2.out" 2>"$work/serve2.err" &
  serve=$!
  for _ in $(seq 100); do grep -q "wall service on" "$work/serve2.out" 2>/dev/null && break; sleep 0.1; done
  port2=$(sed -n 's/^dfbwall: wall service on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve2.out")
  [ -n "$port2" ] || fail "serve (composite) did not start"
  mpi -np 1 "$DFBWALL" --renderer primary --size 250x170 --frames 1 --quiet \
    --image "$work/prim-a.png" || fail "reference a (primary)"
  mpi -np 1 "$DFBWALL" --renderer primary --size 200x150 --frames 1 --quiet \
    --image "$work/prim-b.png" || fail "reference b (primary)"
  "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
    -np 2 "$DFBWALL" --connect "127.0.0.1:$port2" --window "$window_a" --renderer primary \
    --codec raw --frames 100000 --capture-every 5 --quiet --timeout 30 --capture "$ca" \
    >"$work/a2.out" 2>&1 &
  a=$!
  until_frame "$ca" r1c1 5 $((20 * scale)) || fail "job a (composite) presents no frame"
  "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
    -np 2 "$DFBWALL" --connect "127.0.0.1:$port2" --window "$window_b" --renderer primary \
    --codec snappy --frames 100000 --capture-every 5 --quiet --timeout 30 --capture "$cb" \
    >"$work/b2.out" 2>&1 &
  b=$!
  until_frame "$cb" r0c0 10 $((20 * scale)) || fail "job b (composite) presents no frame"
  until_frame "$ca" r1c1 $(($(newest "$ca" r1c1) + 10)) $((20 * scale)) ||
    fail "job a (composite) stopped presenting when b came"
  kill -USR1 "$a" "$b"
  wait "$a" || fail "job a (composite) did not end well"
  wait "$b" || fail "job b (composite) did not end well"
  a="" b=""
  kill -USR1 "$serve"
  for _ in $(seq $((100 * scale))); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$serve" 2>/dev/null && fail "serve (composite) did not stop on SIGUSR1"
  wait "$serve" || fail "serve (composite) exited non-zero after SIGUSR1"
  serve=""
  "$COMPARE" --composite "$window_a+$window_b" "$layout" "$work/wall" \
    "$work/prim-a.png+$work/prim-b.png" any "#000000" || fail "the wall's captures of two jobs"
  # The other order is another picture: the comparison sees which window is on top.
  if "$COMPARE" --composite "$window_b+$window_a" "$layout" "$work/wall" \
    "$work/prim-b.png+$work/prim-a.png" any "#000000" >/dev/null 2>&1; then
    fail "the captures also equal the windows in the other order"
  fi
}
if [ "${2:-}" = glfw ]; then
  composite
  echo "PASS: two jobs at once in GLFW windows: the displays show both windows, the newer on top, byte for byte"
  exit 0
fi
if [ "${2:-}" = composite ]; then
  composite --offscreen
  echo "PASS: two jobs at once (raw, snappy): the wall's captures show both windows, the newer on top, byte for byte"
  exit 0
fi
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen 127.0.0.1:0 \
  --offscreen --timeout "$timeout" --capture-root "$work" --max-jobs 2 \
  --background "#000000" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
port=$(sed -n 's/^dfbwall: wall service on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve.out")
[ -n "$port" ] || fail "serve did not start"

# The one-process renders of both windows at frame 10.
mpi -np 1 "$DFBWALL" --renderer pattern --size 250x170 --frames 10 --quiet \
  --image "$work/ref-a.png" || fail "reference a"
mpi -np 1 "$DFBWALL" --renderer pattern --size 200x150 --frames 10 --quiet \
  --image "$work/ref-b.png" || fail "reference b"

# Job a: 90..340 x 70..240, all four displays; job b: 20..220 x 20..170, over a's top-left.
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np 2 "$DFBWALL" --connect "127.0.0.1:$port" --window "$window_a" --renderer pattern \
  --frames 100000 --capture-every 10 --quiet --timeout 30 --capture "$work/a" \
  >"$work/a.out" 2>&1 &
a=$!
until_frame "$work/a" r1c1 10 $((20 * scale)) || fail "job a presents no frame"
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np 2 "$DFBWALL" --connect "127.0.0.1:$port" --window "$window_b" --renderer pattern \
  --frames 100000 --capture-every 10 --quiet --timeout 30 --capture "$work/b" \
  >"$work/b.out" 2>&1 &
b=$!
until_frame "$work/b" r0c0 10 $((20 * scale)) || fail "job b presents no frame while a runs"
kill -0 "$a" 2>/dev/null || fail "job a ended when b came"

# A third job: busy.
if mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --renderer pattern --frames 1 --quiet \
  --timeout 30 >"$work/c.out" 2>&1; then
  fail "a third job was taken"
fi
grep -q "busy: 2 jobs are on the wall" "$work/c.out" || fail "the third job was not told busy"

# Each job's captures: its window's part, equal to its one-process render.
"$COMPARE" --window "$window_a" "$layout" "$work/a" "$work/ref-a.png" 10 || fail "job a's captures"
"$COMPARE" --window "$window_b" "$layout" "$work/b" "$work/ref-b.png" 10 || fail "job b's captures"

# kill -9 of one of a's ranks: b goes on presenting, well within the timeout.
rank=$(pgrep -P "$a" -f dfbwall | head -1)
[ -n "$rank" ] || fail "no rank of job a"
kill -9 "$rank"
before=$(newest "$work/b" r0c0)
until_frame "$work/b" r0c0 $((before + 20)) $((timeout / 2)) ||
  fail "job b froze after a's rank died (frame $before, then $(newest "$work/b" r0c0))"
kill -0 "$b" 2>/dev/null || fail "job b ended when a died"
after=$(newest "$work/b" r0c0)
# a's mpirun ends its other rank; the wall's stop ends b (told so: it exits non-zero).
wait "$a" 2>/dev/null || true
a=""
kill -USR1 "$serve"
for _ in $(seq $((100 * scale))); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
kill -0 "$serve" 2>/dev/null && fail "serve did not stop on SIGUSR1"
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""
if wait "$b"; then fail "job b did not hear that the wall stopped"; fi
b=""
grep -q "the wall is shutting down" "$work/b.out" || fail "job b was not told the wall stopped"
echo "PASS: two jobs at once in overlapping windows equal their one-process renders; a third busy; b goes on after a's rank died (frame $before, then $after)"
