#!/usr/bin/env bash
# The wall as a service (README, "A wall that stays up"): one `dfbwall serve` that is never
# restarted takes render jobs one after another, each a separate mpirun.
#   service_test.sh jobs-in-a-row LAYOUT
# Jobs: the pattern (raw), scivis with 4 bricks (snappy), the path tracer (jpeg). Raw and Snappy
# captures equal the one-process render byte for byte (the pattern's whole-wall preview too); a JPEG job's captures exist and are a
# picture. Render rank 0 receives 0 pixel bytes. A second job while one is connected is refused
# at once with the busy error; a job queued behind it (--wait) and killed leaves the queue at
# once; kill -9 of a render rank of a running job leaves the wall running, the wall drops the job
# as soon as its connection closes (well within its --timeout) and the next job works without
# --wait. SIGUSR1 stops the wall with exit 0.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
serve="" long="" queued=""
cleanup() {
  for p in $long $queued $serve; do kill -9 "$p" 2>/dev/null || true; done
  pkill -9 -f "$work" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- serve:"; cat "$work/serve.out" "$work/serve.err" 2>/dev/null; exit 1; }
# The pid of the dfbwall process (not mpirun) whose command line holds $1.
rankOf() {
  local rank=""
  for p in $(pgrep -f -- "$1"); do [ "$(cat /proc/$p/comm)" = dfbwall ] && rank=$p; done
  echo "$rank"
}
# waitLog PATTERN SECONDS: until serve's log has a line matching PATTERN (false after SECONDS).
waitLog() {
  local until=$(($(date +%s) + $2))
  while ! grep -qE "$1" "$work/serve.err"; do [ "$(date +%s)" -lt "$until" ] || return 1; sleep 0.1; done
}
since() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN {print b - a}'; }
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }
field() { grep -o "\"$2\": *[0-9.]*" "$1" | sed 's/.*: *//'; }

layout=$2
# Long enough that a job dropped at its connection's close is told apart from one dropped at
# the timeout.
timeout=$((20 * ${DFBWALL_TIME_SCALE:-1}))
port=$((20000 + $$ % 20000))
# Straight, not through mpi(): $! must be mpirun itself (it forwards SIGUSR1 to the wall).
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" \
  --offscreen --max-jobs 1 --timeout "$timeout" --stats "$work/serve.jsonl" --capture-root "$work" \
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

# A job queued behind it (--wait) is killed while it waits: its connection closes and it leaves
# the queue at once.
mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$port" --wait --renderer pattern --frames 9 --quiet \
  --timeout 30 >"$work/queued.out" 2>&1 &
queued=$!
waitLog "queued a job from" 20 || fail "the job with --wait was not queued"
rank=$(rankOf "--connect 127.0.0.1:$port --wait --renderer pattern --frames 9")
[ -n "$rank" ] || fail "no rank of the queued job"
kill -9 "$rank"
start=$(date +%s.%N)
waitLog "a queued job from .* left the queue: its connection closed" $((timeout / 2)) ||
  fail "the killed queued job did not leave the queue within $((timeout / 2)) s (--timeout $timeout)"
left=$(since "$start")
wait "$queued" 2>/dev/null || true
queued=""

# kill -9 of one render rank of the running job: mpirun ends its other ranks, rank 0's connection
# closes, and the wall drops the job at once (not after its --timeout) and goes on.
rank=$(rankOf "--connect 127.0.0.1:$port --renderer pattern --frames 0")
[ -n "$rank" ] || fail "no rank of the running job"
kill -9 "$rank"
start=$(date +%s.%N)
wait "$long" 2>/dev/null || true
long=""
kill -0 "$serve" || fail "the wall died with the job"
waitLog "the job from .* ended after frame [0-9]+ \(its connection closed\)" $((timeout / 2)) ||
  fail "the wall did not drop the killed job within $((timeout / 2)) s (--timeout $timeout)"
grep -q "dropping the job from .*: its connection closed" "$work/serve.err" ||
  fail "the wall did not say it dropped the killed job because its connection closed"
# The next job, without --wait: the wall is free well before the timeout.
job after 2 snappy --renderer pattern
next=$(since "$start")
awk -v t="$next" -v l="$timeout" 'BEGIN {exit !(t < l / 2)}' ||
  fail "the job after the kill was done $next s after it, not within half the --timeout ($timeout s)"
"$COMPARE" "$layout" "$work/after" "$work/after-full.png" 2 || fail "the job after the kill"
[ "$(wc -l <"$work/serve.jsonl")" -ge 6 ] || fail "serve --stats has fewer than 6 job lines"

kill -USR1 "$serve"
for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$serve" 2>/dev/null; then fail "serve did not stop on SIGUSR1"; fi
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""
echo "PASS: 5 jobs on one wall (raw, snappy, jpeg, killed, after), busy refused in ${took}s, a killed queued job left the queue ${left}s after the kill, the job after the killed one done ${next}s after it (--timeout $timeout)"
