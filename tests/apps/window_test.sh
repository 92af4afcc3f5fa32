#!/usr/bin/env bash
# A job in a window of a service wall (docs/service.md, "A job in a window").
#   window_test.sh LAYOUT
# One `dfbwall serve --background "#000000"`; jobs of the pattern renderer with --window:
#  - a window across display borders, not aligned to tiles (raw, then snappy): each display's
#    capture is the window's part of it and equals that part of a one-process render of the
#    window (W x H), byte for byte, as does the job's wall preview;
#  - a window named by a display (its rectangle);
#  - --dry-run prints the window's directory;
#  - windows the wall refuses (outside its canvas, an unknown display, bezels only): a clear
#    error, exit non-zero; --window without --connect is refused too;
#  - then --window full: the captures equal the one-process render of the whole canvas.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
serve="" job="" job2=""
cleanup() {
  # A job's mpirun and its ranks (killed alone it would leave them running).
  for p in $job $job2; do kill -9 $(pgrep -P "$p") "$p" 2>/dev/null || true; done
  [ -n "$serve" ] && kill -9 "$serve" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- serve:"; cat "$work/serve.out" "$work/serve.err" 2>/dev/null; exit 1; }
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }

layout=$1
port=""  # serve listens on port 0; the port it took is read from its first line
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen 127.0.0.1:0 \
  --offscreen --timeout $((5 * ${DFBWALL_TIME_SCALE:-1})) --capture-root "$work" \
  --background "#000000" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!

# job NAME WINDOW CODEC [dfbwall options]: 2 ranks of the pattern in WINDOW.
job() {
  local name=$1 window=$2 codec=$3; shift 3
  mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$port" --window "$window" --codec "$codec" \
    --renderer pattern --frames 2 --quiet --timeout 30 --capture "$work/$name" "$@" ||
    fail "job $name failed"
}
# reference NAME SIZE: the one-process render of the pattern at SIZE (the window's; the pattern
# does not depend on the tile size).
reference() {
  mpi -np 1 "$DFBWALL" --renderer pattern --size "$2" --frames 2 --quiet \
    --image "$work/$1.png" || fail "reference $1 failed"
}
# 90..340 x 70..240 of the 2x2 wall's 412x310: all four displays and the bezels' cross.
window=90,70,250,170
# The one-process references render at once, while the wall starts (process starts are most of
# this test's time on a loaded host).
reference window 250x170 &
references=($!)
reference display 200x150 &
references+=($!)
reference whole "$(canvas "$layout")" &
references+=($!)
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
port=$(sed -n 's/^dfbwall: wall service on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve.out")
[ -n "$port" ] || fail "serve did not start"
for r in "${references[@]}"; do wait "$r" || fail "a reference failed"; done
job raw "$window" raw --tile-size 32
"$COMPARE" --window "$window" "$layout" "$work/raw" "$work/window.png" 2 || fail "window job (raw)"
job snappy "$window" snappy
"$COMPARE" --window "$window" "$layout" "$work/snappy" "$work/window.png" 2 ||
  fail "window job (snappy)"
for d in r0c0 r0c1 r1c0 r1c1; do
  [ -f "$work/raw/$d/frame-000002.png" ] || fail "no capture of display $d"
done
job display r1c1 snappy --tile-size 48
"$COMPARE" --window r1c1 "$layout" "$work/display" "$work/display.png" 2 ||
  fail "window of display r1c1"
[ ! -e "$work/display/r0c0/frame-000002.png" ] || fail "a display outside the window was captured"

# --dry-run shows the window's directory.
mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --window "$window" --dry-run >"$work/dry.out" 2>&1 ||
  fail "--dry-run with a window"
grep -q "canvas 250x170, 4 displays" "$work/dry.out" && grep -q "window 90,70,250,170 of the wall" "$work/dry.out" &&
  grep -q "display r1c1      128x80   at (122, 90)" "$work/dry.out" || { cat "$work/dry.out"; fail "--dry-run does not show the window"; }

# Windows the wall refuses: the job says why and exits non-zero; the wall goes on. The refused
# jobs run at once (none of them is taken, so none waits for another).
refused() {
  local window=$1 reason=$2 out=$work/refused-$1.out
  if mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --window "$window" --renderer pattern \
    --frames 1 --quiet --timeout 30 >"$out" 2>&1; then
    fail "the window $window was accepted"
  fi
  grep -q "$reason" "$out" || { cat "$out"; fail "no reason for refusing $window"; }
}
refused 300,200,200,200 "is not inside the wall's canvas (412x310)" &
refusals=($!)
refused nope "the wall has no display of that name (r0c0, r0c1, r1c0, r1c1)" &
refusals+=($!)
refused 201,151,10,8 "touches no display" &
refusals+=($!)
if mpi -np 1 "$DFBWALL" --renderer pattern --size 64x64 --frames 1 --window 0,0,10,10 \
  --image "$work/x.png" >"$work/noconnect.out" 2>&1; then
  fail "--window without --connect was accepted"
fi
grep -q "\-\-window is for --connect" "$work/noconnect.out" || { cat "$work/noconnect.out"; fail "no reason for --window without --connect"; }
for r in "${refusals[@]}"; do wait "$r" || fail "a window was not refused as it should be"; done
# The next job (the whole canvas) is served as ever.
job full full snappy
"$COMPARE" "$layout" "$work/full" "$work/whole.png" 2 || fail "--window full"
grep -q "window 90,70,250,170" "$work/serve.err" || fail "serve did not log the job's window"

kill -USR1 "$serve"
for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$serve" 2>/dev/null; then fail "serve did not stop on SIGUSR1"; fi
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""

# Converged jobs in windows that leave out wall processes (which have no pieces to wait for),
# two at once on a serve of its own with a short timeout: one in r1c1 (the head is out of it),
# one in r0c0 (the head is its only process). Both idle past the timeout: no process is dropped;
# a camera change through a job's control API brings new frames; SIGUSR1 stops each after the
# frame it names, and the wall names the same frame (none presented past the job's last). Then
# kill -9 of a rank of a job in r1c0: the wall drops it at once and takes the next job.
short=$((2 * ${DFBWALL_TIME_SCALE:-1}))
rm -f "$work/serve.out" "$work/serve.err"  # the first serve's
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen 127.0.0.1:0 \
  --offscreen --timeout "$short" --max-jobs 2 --background "#000000" \
  >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
port2=$(sed -n 's/^dfbwall: wall service on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve.out")
[ -n "$port2" ] || fail "the second serve did not start"
DFBWALL_CONTROL_TOKEN=$(od -An -N16 -tx1 /dev/urandom | tr -d ' \n')
export DFBWALL_CONTROL_TOKEN
auth="Authorization: Bearer $DFBWALL_CONTROL_TOKEN"
# status BASE FIELD: the job's /api/status field.
status() { curl -sf -H "$auth" "$1/api/status" | python3 -c "import json, sys; print(json.load(sys.stdin)['$2'])"; }
# until_true SECONDS WHAT COMMAND...
until_true() {
  local seconds=$1 what=$2; shift 2
  for _ in $(seq $((seconds * 10))); do "$@" 2>/dev/null && return 0; sleep 0.1; done
  cat "$work"/idle-*.out; fail "$what: not within $seconds s"
}
# idle_job WINDOW: a converged primary job (1 sample per pixel) with its control API, in the
# background (mpirun itself: signals reach its ranks), its output in idle-WINDOW.out.
idle_job() {
  "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
    -np 2 "$DFBWALL" --connect "127.0.0.1:$port2" --window "$1" --renderer primary \
    --frames 0 --max-spp 1 --timeout 30 --control 127.0.0.1:0 >"$work/idle-$1.out" 2>&1 &
}
base_of() { grep -o 'http://[0-9.]*:[0-9]*' "$work/idle-$1.out" | head -n1; }
idle() { [ "$(status "$(base_of "$1")" idle)" = True ]; }
# stop_job PID WINDOW: SIGUSR1; the job exits 0 after the frame it names, and the wall's log
# names the same one for the job that ended next.
ended=0
stop_job() {
  kill -USR1 "$1"
  wait "$1" || { cat "$work/idle-$2.out"; fail "the idle job in $2 exited non-zero on SIGUSR1"; }
  local last
  last=$(grep -o "stopped after frame [0-9]*" "$work/idle-$2.out" | grep -o "[0-9]*$")
  [ -n "$last" ] || { cat "$work/idle-$2.out"; fail "the job in $2 did not say its last frame"; }
  ended=$((ended + 1))
  until_true 10 "the wall ending the job in $2" \
    sh -c "[ \$(grep -c 'ended after frame' '$work/serve.err') -ge $ended ]"
  grep "ended after frame" "$work/serve.err" | sed -n "${ended}p" | grep -q "ended after frame $last\$" ||
    fail "the wall did not end the job in $2 after its last frame, $last"
}
idle_job r1c1
job=$!
idle_job r0c0
job2=$!
until_true 30 "the converged job in r1c1" idle r1c1
until_true 30 "the converged job in r0c0" idle r0c0
sleep $((short + 1))
grep -q "lost wall process" "$work/serve.err" && fail "a wall process was dropped while the jobs idled"
a=$(base_of r1c1)
frame=$(status "$a" presented)
curl -sf -H "$auth" -d '{"orbit": 10}' "$a/api/camera" >/dev/null || fail "camera change refused"
until_true 10 "new frames after the camera change" sh -c "[ \$(curl -sf -H '$auth' '$a/api/status' | python3 -c 'import json, sys; print(json.load(sys.stdin)[\"presented\"])') -gt $frame ]"
stop_job "$job" r1c1
job=""
stop_job "$job2" r0c0
job2=""
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np 2 "$DFBWALL" --connect "127.0.0.1:$port2" --window r1c0 --renderer primary \
  --frames 0 --max-spp 1 --timeout 30 >"$work/idle-r1c0.out" 2>&1 &
job=$!
until_true 30 "the job in r1c0 on the wall" grep -q "window r1c0" "$work/serve.err"
kill -9 "$(pgrep -P "$job" -f dfbwall | head -1)"
wait "$job" 2>/dev/null || true
job=""
until_true 1 "the wall dropping the killed job at once" grep -q "dropping the job from .*: its connection closed" "$work/serve.err"
mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port2" --renderer pattern --frames 2 --quiet \
  --timeout 30 >"$work/next.out" 2>&1 || { cat "$work/next.out"; fail "the job after the killed one"; }
kill -USR1 "$serve"
for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
kill -0 "$serve" 2>/dev/null && fail "the second serve did not stop on SIGUSR1"
wait "$serve" || fail "the second serve exited non-zero after SIGUSR1"
serve=""
echo "PASS: window jobs (raw, snappy, a display) equal the one-process render; 3 bad windows refused; the next job (full) too; idle jobs in windows that leave out processes idle, steer and stop cleanly"
