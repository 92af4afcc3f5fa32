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
serve=""
cleanup() {
  [ -n "$serve" ] && kill -9 "$serve" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- serve:"; cat "$work/serve.out" "$work/serve.err" 2>/dev/null; exit 1; }
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }

layout=$1
port=$((20000 + $$ % 20000))
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" \
  --offscreen --timeout $((5 * ${DFBWALL_TIME_SCALE:-1})) --capture-root "$work" \
  --background "#000000" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
grep -q "wall service on 127.0.0.1:$port" "$work/serve.out" || fail "serve did not start"

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
reference window 250x170
job raw "$window" raw --tile-size 32
"$COMPARE" --window "$window" "$layout" "$work/raw" "$work/window.png" 2 || fail "window job (raw)"
job snappy "$window" snappy
"$COMPARE" --window "$window" "$layout" "$work/snappy" "$work/window.png" 2 ||
  fail "window job (snappy)"
for d in r0c0 r0c1 r1c0 r1c1; do
  [ -f "$work/raw/$d/frame-000002.png" ] || fail "no capture of display $d"
done
reference display 200x150
job display r1c1 snappy --tile-size 48
"$COMPARE" --window r1c1 "$layout" "$work/display" "$work/display.png" 2 ||
  fail "window of display r1c1"
[ ! -e "$work/display/r0c0/frame-000002.png" ] || fail "a display outside the window was captured"

# --dry-run shows the window's directory.
mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --window "$window" --dry-run >"$work/dry.out" 2>&1 ||
  fail "--dry-run with a window"
grep -q "canvas 250x170, 4 displays" "$work/dry.out" && grep -q "window 90,70,250,170 of the wall" "$work/dry.out" &&
  grep -q "display r1c1      128x80   at (122, 90)" "$work/dry.out" || { cat "$work/dry.out"; fail "--dry-run does not show the window"; }

# Windows the wall refuses: the job says why and exits non-zero; the wall goes on.
refused() {
  local window=$1 reason=$2
  if mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --window "$window" --renderer pattern \
    --frames 1 --quiet --timeout 30 >"$work/refused.out" 2>&1; then
    fail "the window $window was accepted"
  fi
  grep -q "$reason" "$work/refused.out" || { cat "$work/refused.out"; fail "no reason for refusing $window"; }
}
refused 300,200,200,200 "is not inside the wall's canvas (412x310)"
refused nope "the wall has no display of that name (r0c0, r0c1, r1c0, r1c1)"
refused 201,151,10,8 "touches no display"
if mpi -np 1 "$DFBWALL" --renderer pattern --size 64x64 --frames 1 --window 0,0,10,10 \
  --image "$work/x.png" >"$work/noconnect.out" 2>&1; then
  fail "--window without --connect was accepted"
fi
grep -q "\-\-window is for --connect" "$work/noconnect.out" || { cat "$work/noconnect.out"; fail "no reason for --window without --connect"; }
# The next job (the whole canvas) is served as ever.
reference whole "$(canvas "$layout")"
job full full snappy
"$COMPARE" "$layout" "$work/full" "$work/whole.png" 2 || fail "--window full"
grep -q "window 90,70,250,170" "$work/serve.err" || fail "serve did not log the job's window"

kill -USR1 "$serve"
for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$serve" 2>/dev/null; then fail "serve did not stop on SIGUSR1"; fi
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""
echo "PASS: window jobs (raw, snappy, a display) equal the one-process render; 3 bad windows refused; the next job (full) too"
