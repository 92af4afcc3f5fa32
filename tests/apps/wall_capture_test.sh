#!/usr/bin/env bash
# A serving wall captures what its displays show (docs/service.md, "What the wall shows, captured").
#   wall_capture_test.sh LAYOUT
#  - serve --capture DIR that cannot be written, or inside --capture-root: a clear error at start,
#    every process exits non-zero;
#  - serve --background "#102030" --capture DIR --capture-every 2, a pattern job in a window
#    across display borders (4 frames): wall frames 2 and 4 of every display equal the
#    background with the one-process render of the window at its offset, byte for byte; frames 1
#    and 3 are not written;
#  - a second job (a display's window, 2 frames): the count goes on over the wall's jobs (its
#    frame 2 is wall frame 6, display r1c1's job and the others' background).
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

layout=$1
np=$(processes "$layout")
port=$((20000 + $$ % 20000))
background="#102030"

# A folder that cannot be made (a file on its path), and one where jobs name theirs: refused.
touch "$work/file"
mkdir -p "$work/root"
# refused REASON [serve options]: serve exits non-zero at start, saying REASON. Under mpirun (every
# process checks its own displays' folders), or as process 0 alone with --alone (quicker).
refused() {
  local reason=$1; shift
  local run=(timeout 60 "$MPIEXEC" --oversubscribe --bind-to none -np "$np" "$DFBWALL")
  if [ "$1" = --alone ]; then shift; run=(timeout 60 "$DFBWALL"); set -- --process 0 "$@"; fi
  if "${run[@]}" serve --wall "$layout" --listen "127.0.0.1:$port" --offscreen --timeout 10 "$@" \
    >"$work/refused.out" 2>&1; then
    fail "serve started with $*"
  fi
  grep -q -- "$reason" "$work/refused.out" || { cat "$work/refused.out"; fail "no reason for refusing $*"; }
}
refused "--capture $work/file/wall: cannot create the folder" --capture "$work/file/wall"
refused "lies inside --capture-root" --alone --capture "$work/root/wall" --capture-root "$work/root"
refused "serve --capture-every K needs --capture DIR" --alone --capture-every 2

# mpirun itself in the background (not a function's subshell): SIGUSR1 goes to it.
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -np "$np" "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" --offscreen \
  --max-jobs 1 --timeout $((5 * ${DFBWALL_TIME_SCALE:-1})) --background "$background" \
  --capture "$work/wall" --capture-every 2 >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
grep -q "wall service on 127.0.0.1:$port" "$work/serve.out" || fail "serve did not start"

# job WINDOW FRAMES: 2 ranks of the pattern in WINDOW.
job() {
  mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$port" --window "$1" --renderer pattern \
    --frames "$2" --quiet --timeout 30 || fail "job in $1 failed"
}
# reference NAME SIZE FRAMES: the one-process render of the pattern's frame FRAMES at SIZE.
reference() {
  mpi -np 1 "$DFBWALL" --renderer pattern --size "$2" --frames "$3" --quiet \
    --image "$work/$1.png" || fail "reference $1 failed"
}
window=90,70,250,170  # all four displays of the 2x2 wall and the bezels' cross
job "$window" 4
job r1c1 2
kill -USR1 "$serve"  # the captures queued are written before serve ends
for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$serve" 2>/dev/null; then fail "serve did not stop on SIGUSR1"; fi
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""

reference f2 250x170 2
reference f4 250x170 4
reference d2 200x150 2
"$COMPARE" --composite "$window" "$layout" "$work/wall" "$work/f2.png" 2 "$background" ||
  fail "wall frame 2"
"$COMPARE" --composite "$window" "$layout" "$work/wall" "$work/f4.png" 4 "$background" ||
  fail "wall frame 4"
"$COMPARE" --composite r1c1 "$layout" "$work/wall" "$work/d2.png" 6 "$background" ||
  fail "wall frame 6 (the second job's frame 2)"
# The comparison tells the background apart: black instead is a mismatch.
if "$COMPARE" --composite "$window" "$layout" "$work/wall" "$work/f2.png" 2 "#000000" 2>/dev/null; then
  fail "wall frame 2 equals a black background too"
fi
for d in r0c0 r0c1 r1c0 r1c1; do
  for f in 1 3 5; do
    [ ! -e "$work/wall/$d/frame-00000$f.png" ] || fail "wall frame $f of $d was captured"
  done
done
count=$(find "$work/wall" -name 'frame-*.png' | wc -l)
[ "$count" -eq 12 ] || { find "$work/wall"; fail "$count captures, expected 3 frames of 4 displays"; }
echo "PASS: 3 bad --capture refused; wall frames 2, 4, 6 of 4 displays equal the background with the window's render (1, 3, 5 not written)"
