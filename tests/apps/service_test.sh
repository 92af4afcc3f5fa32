#!/usr/bin/env bash
# The wall as a service (README, "A wall that stays up"): one `dfbwall serve` that is never
# restarted takes render jobs one after another, each a separate mpirun.
#   service_test.sh jobs-in-a-row LAYOUT
# Jobs: the pattern (raw), scivis with 4 bricks (snappy), the path tracer (jpeg). Raw and Snappy
# captures equal the one-process render byte for byte (the pattern's whole-wall preview too); a JPEG job's captures exist and are a
# picture. Render rank 0 receives 0 pixel bytes. A second job while one is connected is refused
# at once with the busy error; kill -9 of a render rank of a running job leaves the wall
# running and the next job works. SIGUSR1 stops the wall with exit 0.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
serve="" long=""
cleanup() {
  for p in $long $serve; do kill -9 "$p" 2>/dev/null || true; done
  pkill -9 -f "$work" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- serve:"; cat "$work/serve.out" "$work/serve.err" 2>/dev/null; exit 1; }
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }
field() { grep -o "\"$2\": *[0-9.]*" "$1" | sed 's/.*: *//'; }

layout=$2
port=$((20000 + $$ % 20000))
# Straight, not through mpi(): $! must be mpirun itself (it forwards SIGUSR1 to the wall).
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" \
  --offscreen --timeout $((5 * ${DFBWALL_TIME_SCALE:-1})) --stats "$work/serve.jsonl" --capture-root "$work" \
  >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
grep -q "wall service on 127.0.0.1:$port" "$work/serve.out" || fail "serve did not start"

# job NAME FRAMES CODEC [dfbwall options]: a job of 2 ranks, then its single-process reference.
job() {
  local name=$1 frames=$2 codec=$3; shift 3
  mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$port" ${wait:-} --codec "$codec" --frames "$frames" --quiet \
    --timeout 30 --capture "$work/$name" --stats "$work/$name.jsonl" "$@" || fail "job $name failed"
  for b in $(field "$work/$name.jsonl" rank0_pixel_bytes_received); do
    [ "$b" = 0 ] || fail "job $name: render rank 0 received $b pixel bytes"
  done
  mpi -np 1 "$DFBWALL" --size "$(canvas "$layout")" --frames "$frames" --quiet \
    --image "$work/$name-full.png" "$@" || fail "reference of $name failed"
}
job pattern 3 raw --renderer pattern
"$COMPARE" "$layout" "$work/pattern" "$work/pattern-full.png" 3 || fail "pattern job (raw)"
# The whole-wall preview: the other processes' pixels reach the head in 64 KiB parts.
"$COMPARE" --preview "$layout" "$work/pattern/wall-000003.png" "$work/pattern-full.png" ||
  fail "the wall preview of the pattern job"
job bricks 2 snappy --renderer scivis --scene builtin:wavelet --bricks 4 --tile-size 32
"$COMPARE" "$layout" "$work/bricks" "$work/bricks-full.png" 2 || fail "bricks job (snappy)"
job cornell 2 jpeg:90 --scene builtin:cornell
for d in "$work"/cornell/*/; do
  [ -f "$d/frame-000002.png" ] || fail "JPEG job: no capture in $d"
  colors=$("$COMPARE" --colors "$d/frame-000002.png")
  [ "$colors" -gt 100 ] || fail "JPEG job: $d shows $colors colours"
done

# A job the wall cannot serve (one display's capture folder cannot be made: a file has its name)
# is refused with the reason; the wall goes on.
mkdir -p "$work/blocked" && touch "$work/blocked/r0c0"
if mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --renderer pattern --frames 1 --quiet \
  --timeout 30 --capture "$work/blocked" >"$work/blocked.out" 2>&1; then
  fail "a job whose capture folder cannot be made was accepted"
fi
grep -q "refused the job: capture folder" "$work/blocked.out" || { cat "$work/blocked.out"; fail "no reason for the refusal"; }

# A job that runs until stopped; a second one meanwhile is refused at once.
mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$port" --renderer pattern --frames 0 --quiet \
  --timeout 30 >"$work/long.out" 2>&1 &
long=$!
for _ in $(seq 100); do grep -q "job from" "$work/serve.err" 2>/dev/null &&
  [ "$(grep -c "job from .*render ranks" "$work/serve.err")" -ge 5 ] && break; sleep 0.1; done
start=$(date +%s.%N)
if mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --renderer pattern --frames 1 --quiet \
  --timeout 60 >"$work/busy.out" 2>&1; then fail "a second job was accepted while one was connected"; fi
grep -q "busy: a job from .* is connected" "$work/busy.out" || { cat "$work/busy.out"; fail "no busy error"; }
took=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
# "At once" is: not after the job's --timeout (60 s); mpirun's own start-up is slow on a loaded host.
awk -v t="$took" 'BEGIN {exit !(t < 30)}' || fail "the busy refusal took $took s (its --timeout is 60 s)"

# kill -9 of one render rank of the running job: the job ends, the wall drops it and goes on.
rank=$(pgrep -f -n -- "--connect 127.0.0.1:$port --renderer pattern --frames 0" | head -1)
for p in $(pgrep -f -- "--connect 127.0.0.1:$port --renderer pattern --frames 0"); do
  [ "$(cat /proc/$p/comm)" = dfbwall ] && rank=$p
done
kill -9 "$rank"
wait "$long" 2>/dev/null || true
long=""
kill -0 "$serve" || fail "the wall died with the job"
# The wall notices within its --timeout (5 s); --wait queues the job until then.
start=$(date +%s.%N)
wait=--wait job after 2 snappy --renderer pattern
next=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
"$COMPARE" "$layout" "$work/after" "$work/after-full.png" 2 || fail "the job after the kill"
grep -q "dropping the job" "$work/serve.err" || fail "the wall did not say it dropped the killed job"
[ "$(wc -l <"$work/serve.jsonl")" -ge 6 ] || fail "serve --stats has fewer than 6 job lines"

kill -USR1 "$serve"
for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$serve" 2>/dev/null; then fail "serve did not stop on SIGUSR1"; fi
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""
echo "PASS: 5 jobs on one wall (raw, snappy, jpeg, killed, after), busy refused in ${took}s, the job after the kill done ${next}s after it"
