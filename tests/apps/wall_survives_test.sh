#!/usr/bin/env bash
# A wall that survives its own processes (README, "A wall that survives its own nodes"), on one
# host: `mpirun --enable-recovery -np 4 dfbwall serve --timeout 3` on the 2x2 layout (display
# r<row>c<col> is wall process 2 * row + col) and a render job with --frames 0 --capture DIR
# --capture-every 1 and a control server.
#  1. kill -9 of wall process 3: within the timeout + 2 s the other three displays present new
#     frames; the job goes on, counts the dropped pieces (wall_pieces_dropped) and its
#     /api/status names r1c1 as lost; the wall's log and --stats name the loss once.
#  2. The documented restart (`dfbwall serve --wall L --process 3 --join HOST:PORT`): within 3 s
#     of joining, r1c1 presents a frame equal to the one-process render of that frame.
#  3. SIGSTOP of process 2 for longer than the timeout: dropped the same way; after SIGCONT it
#     rejoins and presents again.
#  4. SIGUSR1 stops the wall (the restarted process too) with exit 0.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
serve="" job="" restarted=""
cleanup() {
  for p in $job $serve $restarted; do kill -9 "$p" 2>/dev/null || true; done
  pkill -9 -f "$work" 2>/dev/null || true
  pkill -CONT -f "serve --wall $layout" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in serve.err job.err restarted.err; do echo "--- $f:"; tail -20 "$work/$f" 2>/dev/null || true; done
  exit 1
}
# now, since, latest, advanced, presentedSince, waitFor, pidOf, freePort
source "$(dirname "${BASH_SOURCE[0]}")/wall_watch.sh"
# The job's control API token (DFBWALL_CONTROL_TOKEN: never on a command line).
DFBWALL_CONTROL_TOKEN=$(od -An -N16 -tx1 /dev/urandom | tr -d ' \n')
export DFBWALL_CONTROL_TOKEN
status() { python3 -c "import json,os,urllib.request; print(json.load(urllib.request.urlopen(urllib.request.Request('http://127.0.0.1:$cport/api/status', headers={'Authorization': 'Bearer ' + os.environ['DFBWALL_CONTROL_TOKEN']})))['lost_displays'])"; }

layout=$1
timeout=3
port=$(freePort) cport=$(freePort)
"$MPIEXEC" --enable-recovery --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -np 4 \
  "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" --offscreen --timeout $timeout \
  --stats "$work/serve.jsonl" --capture-root "$work" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
waitFor 20 grep -q "wall service on" "$work/serve.out" || fail "serve did not start"
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -np 2 "$DFBWALL" \
  --connect "127.0.0.1:$port" --renderer pattern --frames 0 --quiet --timeout 30 \
  --capture "$work/cap" --capture-every 1 --stats "$work/job.jsonl" \
  --control "127.0.0.1:$cport" >"$work/job.out" 2>"$work/job.err" &
job=$!
waitFor 30 advanced 5 r0c0 r0c1 r1c0 r1c1 || fail "the job's frames did not reach the wall"

# 1. kill -9 of wall process 3.
victim=$(pidOf 3)
[ -n "$victim" ] || fail "no wall process 3"
kill -9 "$victim"
start=$(now)
waitFor $((timeout + 5)) grep -q "lost wall process 3" "$work/serve.err" || fail "process 3 was not dropped"
frame=$(latest r0c0)
waitFor 5 advanced "$frame" r0c0 r0c1 r1c0 || fail "the other displays did not present new frames"
resumed=$(presentedSince "$start" "$frame" r0c0 r0c1 r1c0)
within "$resumed" $((timeout + 2)) ||
  fail "the other displays presented again only ${resumed} s after the kill (timeout $timeout s)"
kill -0 "$job" || fail "the job stopped when a wall process died"
grep -q "lost wall process 3" "$work/job.err" || fail "the job was not told about the loss"
waitFor 5 sh -c "$(declare -f status); cport=$cport; status | grep -q r1c1" ||
  fail "/api/status does not name r1c1 as lost: $(status)"
waitFor 5 grep -q '"wall_pieces_dropped":[1-9]' "$work/job.jsonl" || fail "no dropped pieces counted"
grep -q '"wall_roster":{"version":1,.*"lost_displays":\["r1c1"\]' "$work/job.jsonl" ||
  fail "the job's --stats do not name the loss of r1c1"
dead=$(latest r1c1)

# 2. The documented restart of process 3.
"$DFBWALL" serve --wall "$layout" --process 3 --join "127.0.0.1:$port" --offscreen \
  --timeout $timeout --capture-root "$work" >"$work/restarted.out" 2>"$work/restarted.err" &
restarted=$!
# Counted from its join, not its launch: starting a process (libraries, OSMesa) is the host's
# load, not the wall's.
waitFor 20 grep -q "joined the wall" "$work/restarted.err" || fail "the restarted process 3 did not join"
start=$(now)
waitFor 10 advanced "$dead" r1c1 || fail "the restarted process 3 presents nothing"
back=$(presentedSince "$start" "$dead" r1c1)
within "$back" 3 || fail "process 3 presented again only ${back} s after it joined"
frame=$(latest r1c1)
rejoinedFrame=$frame
cp "$work/cap/r1c1/frame-$(printf %06d "$frame").png" "$work/rejoined.png"
mkdir -p "$work/check/r1c1" && cp "$work/rejoined.png" "$work/check/r1c1/frame-$(printf %06d "$frame").png"
"$MPIEXEC" --oversubscribe -np 1 "$DFBWALL" --size "$("$COMPARE" --info "$layout" | cut -d' ' -f2)" \
  --renderer pattern --frames "$frame" --quiet --image "$work/full.png" || fail "the reference render failed"
"$COMPARE" "$layout" "$work/check" "$work/full.png" "$frame" r1c1 || fail "the rejoined display's frame $frame"
waitFor 5 sh -c "$(declare -f status); cport=$cport; ! status | grep -q r1c1" ||
  fail "/api/status still names r1c1 as lost: $(status)"

# 3. SIGSTOP of process 2 for longer than the timeout, then SIGCONT.
stopped=$(pidOf 2)
[ -n "$stopped" ] || fail "no wall process 2"
kill -STOP "$stopped"
waitFor $((timeout + 5)) grep -q "lost wall process 2" "$work/serve.err" || fail "the stopped process 2 was not dropped"
frame=$(latest r0c0)
waitFor 5 advanced "$frame" r0c0 r0c1 r1c1 || fail "the others did not go on without process 2"
halted=$(latest r1c0)
kill -CONT "$stopped"
# Continued, it may still write the capture of a frame presented before the stop; what counts is
# a frame after it joined again.
waitFor 10 grep -q "wall process 2 on .* is back in the wall" "$work/serve.err" ||
  fail "process 2 did not join again after SIGCONT"
halted=$(latest r1c0)
waitFor 10 advanced "$halted" r1c0 || fail "process 2 did not present again after SIGCONT"
kill -0 "$job" || fail "the job stopped"

# Every loss and every return is named once, in the log and in --stats.
[ "$(grep -c "lost wall process 3" "$work/serve.err")" = 1 ] || fail "the loss of process 3 logged more than once"
grep -q '"event":"lost","process":3' "$work/serve.jsonl" || fail "no lost event for process 3 in --stats"
grep -q '"event":"rejoined","process":2' "$work/serve.jsonl" || fail "no rejoined event for process 2 in --stats"

# 4. Stop the job, then the wall.
kill -TERM "$job"
waitFor 20 sh -c "! kill -0 $job 2>/dev/null" || fail "the job did not stop on SIGTERM"
job=""
kill -USR1 "$serve"
waitFor 20 sh -c "! kill -0 $serve 2>/dev/null && ! kill -0 $restarted 2>/dev/null" || {
  ps -eo pid,stat,wchan:24,args | grep "[s]erve --wall $layout" | cut -c1-160
  fail "the wall did not stop on SIGUSR1"
}
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
wait "$restarted" || fail "the restarted process 3 exited non-zero"
serve="" restarted=""
echo "PASS: after kill -9 the other displays presented again in ${resumed} s; the restarted process presented frame $rejoinedFrame (equal to the one-process render) ${back} s after its start; SIGSTOP/SIGCONT dropped and rejoined process 2"
