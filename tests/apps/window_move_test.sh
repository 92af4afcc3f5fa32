#!/usr/bin/env bash
# Moving and resizing a running job's window (docs/service.md, "Moving and resizing a window").
#   window_move_test.sh LAYOUT (the 2x2 wall)
# One `dfbwall serve --max-jobs 2 --background "#000000"`: job b path-traced (--max-spp 1: it
# converges at its first frame and idles), then job a of the pattern renderer, in windows across
# display borders. Job a's window is moved and resized mid-run, then moved alone; then b's, idle,
# is moved and resized (DFBWALL_TEST_MOVES, the head's own trigger until the wall's control port
# routes it):
#  - a job re-plans without reconnecting and says from which frame; an idle one wakes up for it;
#  - from that frame on its captures (its window's part of each display, and its wall preview)
#    are at the new place and size, equal byte for byte to the one-process render of that frame
#    at the new size (the path tracer's accumulation starts over: its first frame's);
#  - the frame before the switch is the old window's;
#  - the other job goes on meanwhile and is never moved with it.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
source "$(dirname "$0")/service_jobs_lib.sh"
# switch_frame JOB N: the frame job JOB's N-th move took over at (what the job printed).
switch_frame() {
  sed -n 's/^dfbwall: the wall moved the window to .* from frame \([0-9]*\)$/\1/p' "$work/$1.out" |
    sed -n "${2}p"
}
# wait_switch JOB N: waits for it and prints it.
wait_switch() {
  for _ in $(seq $((200 * scale))); do [ -n "$(switch_frame "$1" "$2")" ] && break; sleep 0.1; done
  switch_frame "$1" "$2"
}
# check_shape FRAME X,Y,W,H: job a's captures of FRAME equal the one-process render at W x H.
check_shape() {
  local size=${2#*,}; size=${size#*,}; size=${size/,/x}
  mpi -np 1 "$DFBWALL" --renderer pattern --size "$size" --frames "$1" --quiet \
    --image "$work/ref-$1.png" || fail "reference of frame $1 at $size"
  "$COMPARE" --window "$2" "$layout" "$work/a" "$work/ref-$1.png" "$1" ||
    fail "job a's frame $1 is not the one-process render in window $2"
}
cornell=(--scene builtin:cornell --spp 1 --max-spp 1 --seed 11)
# check_traced FRAME X,Y,W,H: job b's captures of FRAME equal the path tracer's first frame at
# W x H in one process.
check_traced() {
  local size=${2#*,}; size=${size#*,}; size=${size/,/x}
  mpi -np 1 "$DFBWALL" "${cornell[@]}" --size "$size" --frames 1 --quiet \
    --image "$work/ref-b-$size.png" || fail "path-traced reference at $size"
  "$COMPARE" --window "$2" "$layout" "$work/b" "$work/ref-b-$size.png" "$1" ||
    fail "job b's frame $1 is not the one-process render in window $2"
}

layout=$1
port=$((20000 + $$ % 20000))
# Job a's window: 90,70,250,170 at first; from its frame 20 on 40,30,300,200 (moved and larger),
# from frame 50 on 100,100,300,200 (moved alone). Job b's: 20,20,200,150, then 160,110,180,120.
first=90,70,250,170 resized=40,30,300,200 moved=100,100,300,200
first_b=20,20,200,150 moved_b=160,110,180,120
DFBWALL_TEST_MOVES="2:20:$resized;2:50:$moved;1:1:$moved_b" "$MPIEXEC" --oversubscribe --bind-to none \
  --mca mpi_yield_when_idle 1 -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" \
  --listen "127.0.0.1:$port" --offscreen --timeout "$timeout" --capture-root "$work" \
  --max-jobs 2 --background "#000000" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
grep -q "wall service on 127.0.0.1:$port" "$work/serve.out" || fail "serve did not start"

# Job b first (never moved: the moves are the second job's), then job a.
mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$port" --window "$first_b" "${cornell[@]}" \
  --frames 0 --capture-every 1 --quiet --timeout 30 --capture "$work/b" >"$work/b.out" 2>&1 &
b=$!
until_frame "$work/b" r0c0 1 $((20 * scale)) || fail "job b presents no frame"
check_traced 1 "$first_b"
mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$port" --window "$first" --renderer pattern \
  --frames 100000 --capture-every 1 --quiet --timeout 30 --capture "$work/a" \
  >"$work/a.out" 2>&1 &
a=$!
until_frame "$work/a" r1c1 5 $((20 * scale)) || fail "job a presents no frame"
check_shape 5 "$first"

# The first move: resized and moved, re-planned without reconnecting.
f1=$(wait_switch a 1)
[ -n "$f1" ] || fail "job a was not moved"
until_frame "$work/a" r0c0 $((f1 + 3)) $((20 * scale)) || fail "job a presents no frame after its move"
check_shape "$f1" "$resized"
check_shape $((f1 + 3)) "$resized"
# Before the switch the window was the old one, at its old size.
check_shape $((f1 - 1)) "$first"

# The second move: the same size elsewhere.
f2=$(wait_switch a 2)
[ -n "$f2" ] || fail "job a was not moved a second time"
until_frame "$work/a" r1c1 $((f2 + 3)) $((20 * scale)) || fail "job a presents no frame after its second move"
check_shape "$f2" "$moved"
check_shape $((f2 + 3)) "$moved"

# Job b, idle all along (converged), is moved now: it wakes up, and from its switch frame shows
# its first frame again, at the new size.
before=$(newest "$work/a" r1c1)
fb=$(wait_switch b 1)
[ -n "$fb" ] || fail "job b was not moved"
until_frame "$work/b" r1c1 "$fb" $((20 * scale)) || fail "job b presents no frame after its move"
check_traced "$fb" "$moved_b"
# Job a went on meanwhile.
until_frame "$work/a" r1c1 $((before + 20)) $((timeout / 2)) || fail "job a stopped presenting"
kill -0 "$a" 2>/dev/null || fail "job a ended"
# Each job moved by its own moves only.
[ "$(grep -c "moved the window" "$work/a.out")" -eq 2 ] || fail "job a was not moved exactly twice"
[ "$(grep -c "moved the window" "$work/b.out")" -eq 1 ] || fail "job b was not moved exactly once"
kill -0 "$b" 2>/dev/null || fail "job b ended"
kill -USR1 "$serve"
for _ in $(seq $((100 * scale))); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""
wait "$a" 2>/dev/null || true
wait "$b" 2>/dev/null || true
a="" b=""
echo "PASS: job a moved and resized at frame $f1 and moved at frame $f2, job b (idle, path-traced) at frame $fb, without reconnecting; each new window's frames equal the one-process render at its size"
