#!/usr/bin/env bash
# Keys and the mouse in a shared wall's GLFW windows steer the job under the cursor
# (docs/service.md, "Several jobs at once"). Under Xvfb, a 2x2 `serve --max-jobs 2` wall with two
# converged primary-renderer jobs side by side (r0c0 and r1c1), each capturing every frame:
#  - a key over the background (display r0c1) steers nobody: no job renders a new frame;
#  - real X events (xdotool, through XTEST) over r0c0 — the right arrow, a drag, a wheel notch —
#    each give job a new frames that differ from its frames before; job b renders nothing new and
#    its every captured frame stays byte-identical;
#  - Esc over a window stops nothing on a shared wall: the wall and both jobs go on.
# Then the same wall with `--max-jobs 1` (one job at a time, presented on the process's main
# thread) and one job in r0c0: a key over the background steers nothing, the right arrow and a
# wheel notch over its window steer it, Esc stops nothing.
#   wall_input_test.sh LAYOUT   (DFBWALL, COMPARE, MPIEXEC in the environment)
set -euo pipefail
if [ -z "${WALL_INPUT_TEST_INNER:-}" ]; then
  # A server number of its own, so a concurrent Xvfb test elsewhere cannot take the same one.
  exec xvfb-run -a -n $((300 + RANDOM % 500)) -s "-screen 0 1280x1024x24 -noreset" \
    env WALL_INPUT_TEST_INNER=1 "$0" "$@"
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
layout=$1
work=$(mktemp -d)
source "$(dirname "$0")/service_jobs_lib.sh"
port=$((20000 + $$ % 20000))
frame() { printf '%s/%s/%s/frame-%06d.png' "$work" "$1" "$2" "$3"; }
# settled JOB DISPLAY: waits until JOB captured a frame and then none for a second (converged,
# idle); prints its newest frame.
settled() {
  local last=-1 now
  for _ in $(seq $((30 * scale))); do
    now=$(newest "$work/$1" "$2")
    [ "$now" -gt 0 ] && [ "$now" -eq "$last" ] && { echo "$now"; return 0; }
    last=$now
    sleep 1
  done
  return 1
}

# start_wall MAX_JOBS: the wall, in GLFW windows on the X server.
start_wall() {
  "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
    -np 4 -x DISPLAY -x XAUTHORITY "$DFBWALL" serve --wall "$layout" \
    --listen "127.0.0.1:$port" --timeout $((8 * scale)) --capture-root "$work" --max-jobs "$1" \
    --background "#000000" >"$work/serve.out" 2>"$work/serve.err" &
  serve=$!
  for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
  grep -q "wall service on 127.0.0.1:$port" "$work/serve.out" || fail "serve did not start"
}
# stop_wall: SIGUSR1, and it exits 0.
stop_wall() {
  kill -USR1 "$serve"
  for _ in $(seq $((100 * scale))); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$serve" 2>/dev/null && fail "serve did not stop on SIGUSR1"
  wait "$serve" || fail "serve exited non-zero after SIGUSR1"
  serve=""
}
start_wall 2
# job WINDOW NAME: a converged primary-renderer job (4 frames, then idle) capturing every frame.
job() {
  "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
    -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --window "$1" --renderer primary \
    --frames 0 --max-spp 4 --capture "$work/$2" --capture-every 1 --quiet --timeout 30 \
    >"$work/$2.out" 2>&1 &
}
job r0c0 a
a=$!
job r1c1 b
b=$!
na=$(settled a r0c0) || fail "job a did not present and settle"
nb=$(settled b r1c1) || fail "job b did not present and settle"
cp "$(frame a r0c0 "$na")" "$work/a-before.png"
echo "settled: job a at frame $na, job b at frame $nb"

win() { xdotool search --sync --name "^$1\$" | head -n1; }
# A key over the background steers nobody.
bg=$(win r0c1)
xdotool mousemove --window "$bg" 100 75 windowfocus --sync "$bg" key --delay 100 Right
sleep 1.5
[ "$(newest "$work/a" r0c0)" -eq "$na" ] || fail "a key over the background steered job a"
[ "$(newest "$work/b" r1c1)" -eq "$nb" ] || fail "a key over the background steered job b"

# changed WHAT: waits until job a captured a frame after $na that differs from its last before.
changed() {
  for _ in $(seq $((150 * scale))); do
    local now
    now=$(newest "$work/a" r0c0)
    if [ "$now" -gt "$na" ] && ! cmp -s "$(frame a r0c0 "$now")" "$work/a-before.png"; then
      sleep 0.5  # its epoch's later frames
      na=$(settled a r0c0) || fail "job a did not settle after $1"
      echo "$1: job a at frame $na, a new picture"
      cp "$(frame a r0c0 "$na")" "$work/a-before.png"
      return 0
    fi
    sleep 0.1
  done
  fail "$1 over job a's window gave it no new frame (newest $(newest "$work/a" r0c0), $na before)"
}
wa=$(win r0c0)
xdotool mousemove --window "$wa" 100 75 windowfocus --sync "$wa" key --delay 100 Right
changed "the right arrow"
xdotool mousemove --window "$wa" 100 75 click 4
changed "a wheel notch"
# 20 px of the window's 200: 18 degrees (more turns the Cornell box's open side away).
xdotool mousemove --window "$wa" 60 75 mousedown 1 mousemove --window "$wa" 70 75 \
  mousemove --window "$wa" 80 75 mouseup 1
changed "a drag"
xdotool key Escape
sleep 1
for p in "$serve" "$a" "$b"; do kill -0 "$p" 2>/dev/null || fail "Esc stopped something on a shared wall"; done

# Job b: nothing new, every frame as it was.
[ "$(newest "$work/b" r1c1)" -eq "$nb" ] || fail "job b rendered new frames while a was steered"
for f in "$work"/b/r1c1/frame-*.png; do
  cmp -s "$f" "$(frame b r1c1 "$nb")" || fail "job b's $(basename "$f") differs from its last"
done

kill -USR1 "$a" "$b"
wait "$a" || fail "job a did not end well"
wait "$b" || fail "job b did not end well"
a="" b=""
stop_wall

# One job at a time: the same keys and wheel steer the one job, over its window only.
rm -rf "$work/a"
port=$((port + 1))
start_wall 1
job r0c0 a
a=$!
na=$(settled a r0c0) || fail "job a did not present and settle on a --max-jobs 1 wall"
cp "$(frame a r0c0 "$na")" "$work/a-before.png"
echo "--max-jobs 1: job a settled at frame $na"
bg=$(win r0c1)
xdotool mousemove --window "$bg" 100 75 windowfocus --sync "$bg" key --delay 100 Right
sleep 1.5
[ "$(newest "$work/a" r0c0)" -eq "$na" ] || fail "a key over the background steered job a (--max-jobs 1)"
wa=$(win r0c0)
xdotool mousemove --window "$wa" 100 75 windowfocus --sync "$wa" key --delay 100 Right
changed "the right arrow (--max-jobs 1)"
xdotool mousemove --window "$wa" 100 75 click 4
changed "a wheel notch (--max-jobs 1)"
xdotool key Escape
sleep 1
for p in "$serve" "$a"; do kill -0 "$p" 2>/dev/null || fail "Esc stopped something on a --max-jobs 1 service wall"; done
kill -USR1 "$a"
wait "$a" || fail "job a did not end well (--max-jobs 1)"
a=""
stop_wall
echo "PASS: a key, a drag and the wheel over one job's wall window steer it alone; the other's frames stay byte-identical; the background and Esc steer nothing; on a --max-jobs 1 wall a key and the wheel over the job's window steer it, over the background and Esc nothing"
