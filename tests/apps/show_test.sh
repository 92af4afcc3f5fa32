#!/usr/bin/env bash
# Pictures beside renders (docs/service.md, "Pictures beside renders"): `dfbwall show` on a 2x2
# wall served with --max-jobs 2 --background "#000000", beside a pattern render job whose window
# overlaps it:
#  - a partly transparent PNG, bilinear, over #203040, raw pieces: the window's part of every
#    display equals the fitted picture computed apart from dfbwall (picture_expected.py: Pillow
#    and numpy), byte for byte;
#  - a JPEG sequence (seq-%04d.jpg), nearest, snappy, --fps 20 --once: frame k is picture k;
#  - a still picture is sent once (one frame in --stats while it stays on the wall), a --loop
#    goes on past the last picture; both stop on SIGUSR1 with exit 0;
#  - the render job beside it is untouched: its captures equal its one-process render;
#  - a missing file, a gap in a sequence and a corrupt picture: one message each, exit non-zero.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
here=$(cd "$(dirname "$0")" && pwd)
expected="/usr/bin/python3 $here/picture_expected.py"
work=$(mktemp -d)
serve="" job="" still=""
cleanup() {
  # mpirun and its ranks (killed alone it would leave them running).
  for p in $job $serve; do kill -9 $(pgrep -P "$p") "$p" 2>/dev/null || true; done
  [ -z "$still" ] || kill -9 "$still" 2>/dev/null || true
  wait 2>/dev/null || true
  [ -n "${KEEP:-}" ] || rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in serve.out job.out show.out; do echo "--- $f:"; cat "$work/$f" 2>/dev/null || true; done
  exit 1
}
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
scale=${DFBWALL_TIME_SCALE:-1}
# newest DIR DISPLAY: the newest captured frame's number (0: none yet).
newest() {
  local f
  f=$(ls "$1/$2" 2>/dev/null | grep -E '^frame-[0-9]+\.png$' | sort | tail -1)
  [ -n "$f" ] || { echo 0; return; }
  f=${f#frame-}; echo $((10#${f%.png}))
}
# frames STATS: the frame lines of a --stats file.
frames() {
  local n
  n=$(grep -c '^{"frame"' "$1" 2>/dev/null) || true
  echo "${n:-0}"
}

layout=$1
port=""  # serve listens on port 0; the port it took is read from its first line
$expected make "$work"
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen 127.0.0.1:0 \
  --offscreen --token show-test --timeout $((8 * scale)) --capture-root "$work" --max-jobs 2 \
  --background "#000000" >"$work/serve.out" 2>&1 &
serve=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
port=$(sed -n 's/^dfbwall: wall service on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$work/serve.out")
[ -n "$port" ] || fail "serve did not start"
show() { "$DFBWALL" show --connect "127.0.0.1:$port" --token show-test --quiet --timeout 30 "$@"; }

# The render job beside the pictures: 20..220 x 20..170, under the first picture's window.
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -np 1 "$DFBWALL" \
  --renderer pattern --size 200x150 --frames 10 --quiet --image "$work/ref-job.png" ||
  fail "the render job's reference"
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --token show-test --window 20,20,200,150 \
  --renderer pattern --frames 100000 --capture-every 10 --quiet --timeout 30 \
  --capture "$work/job" >"$work/job.out" 2>&1 &
job=$!
for _ in $(seq $((200 * scale))); do [ "$(newest "$work/job" r0c0)" -ge 10 ] && break; sleep 0.1; done
[ "$(newest "$work/job" r0c0)" -ge 10 ] || fail "the render job presents no frame"

# A PNG with transparency, bilinear, over #203040, on top of the render job, across all four
# displays.
window=90,70,250,170
show --window "$window" --once --codec raw --filter bilinear --background "#203040" \
  --capture "$work/png" "$work/plot.png" >"$work/show.out" 2>&1 || fail "show plot.png"
$expected fit "$work/plot.png" 250 170 bilinear "#203040" "$work/expected-png.png"
"$COMPARE" --window "$window" "$layout" "$work/png" "$work/expected-png.png" 1 ||
  fail "the PNG on the wall is not the fitted picture"

# A JPEG sequence, nearest, snappy, 20 pictures a second, each frame captured.
window=150,100,160,120
started=$(date +%s%N)
show --window "$window" --once --fps 20 --filter nearest --capture "$work/seq" --capture-every 1 \
  "$work/seq-%04d.jpg" >"$work/show.out" 2>&1 || fail "show seq-%04d.jpg"
took_ms=$((($(date +%s%N) - started) / 1000000))
for k in 1 2 3; do
  $expected fit "$work/seq-000$k.jpg" 160 120 nearest "#000000" "$work/expected-seq-$k.png"
  "$COMPARE" --window "$window" "$layout" "$work/seq" "$work/expected-seq-$k.png" "$k" ||
    fail "frame $k of the sequence is not picture $k"
done
[ "$(newest "$work/seq" r1c1)" -eq 3 ] || fail "the sequence of 3 pictures had more frames"

# A still picture stays on the wall, sent once; SIGUSR1 ends it with exit 0. (In a window that
# touches every display: a job stopped early in a window that leaves out wall processes fails on
# main, whatever it renders.)
"$DFBWALL" show --connect "127.0.0.1:$port" --token show-test --quiet --window "$window" \
  --stats "$work/still.json" "$work/plot.png" >"$work/show.out" 2>&1 &
still=$!
for _ in $(seq $((100 * scale))); do [ "$(frames "$work/still.json")" -ge 1 ] && break; sleep 0.1; done
sleep 1
kill -0 "$still" 2>/dev/null || fail "a still picture did not stay on the wall"
kill -USR1 "$still"
wait "$still" || fail "show of a still picture did not end cleanly on SIGUSR1"
still=""
[ "$(frames "$work/still.json")" -eq 1 ] ||
  fail "a still picture was sent $(frames "$work/still.json") times in 1 s, not once"

# --loop goes on past the last picture.
"$DFBWALL" show --connect "127.0.0.1:$port" --token show-test --quiet --window "$window" --loop \
  --fps 20 --stats "$work/loop.json" "$work/seq-%04d.jpg" >"$work/show.out" 2>&1 &
still=$!
for _ in $(seq $((100 * scale))); do [ "$(frames "$work/loop.json")" -ge 8 ] && break; sleep 0.1; done
kill -USR1 "$still"
wait "$still" || fail "show --loop did not end cleanly on SIGUSR1"
still=""
looped=$(frames "$work/loop.json")
[ "$looped" -ge 8 ] || fail "--loop of 3 pictures stopped after $looped frames"

# The render job went on beside the pictures, its window's captures its own.
kill -0 "$job" 2>/dev/null || fail "the render job ended while pictures were shown"
"$COMPARE" --window 20,20,200,150 "$layout" "$work/job" "$work/ref-job.png" 10 ||
  fail "the render job's captures"

# Bad input: one message each, exit non-zero, before the wall hears of it.
expect_error() {  # expect_error MESSAGE ARGS...
  local message=$1; shift
  if show "$@" >"$work/show.out" 2>&1; then fail "show $* was taken"; fi
  grep -qF "$message" "$work/show.out" || fail "show $*: no '$message'"
}
expect_error "nope.png: no such file" "$work/nope.png"
rm "$work/seq-0002.jpg"
expect_error "the sequence has a gap: $work/seq-0002.jpg is missing" "$work/seq-%04d.jpg"
head -c 300 "$work/plot.png" >"$work/cut.png"
expect_error "cut.png: a corrupt PNG" "$work/cut.png"
/usr/bin/python3 -c "from PIL import Image; Image.new('RGB', (3000, 3000)).save('$work/big.png')"
expect_error "big.png: the 3000x3000 picture needs" --memory-limit 30M "$work/big.png"
echo "PASS: a PNG and a JPEG sequence on the wall equal the fitted pictures computed apart; the" \
  "sequence (3 pictures at 20 fps) took ${took_ms} ms; a still picture sent once; --loop went" \
  "on ($looped frames); the render job beside them untouched; bad pictures refused"
