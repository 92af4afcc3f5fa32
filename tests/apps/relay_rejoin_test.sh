#!/usr/bin/env bash
# A wall process that dies and is restarted while a job renders through `dfbwall relay` (README,
# "A wall that stays up"): the wall's Rosters reach the job rewritten (the relay's endpoints), and
# the relay moves its connection to the restarted process's new piece socket.
#   `mpirun --enable-recovery -np 4 dfbwall serve --timeout 3` on the 2x2 layout (display
#   r<row>c<col> is wall process 2 * row + col), a relay, a job through it with --frames 0
#   --capture DIR --capture-every 1.
#  1. kill -9 of wall process 3: the other three displays present new frames; the job goes on.
#  2. The documented restart (`dfbwall serve --process 3 --join`): the relay logs that process 3
#     moved to a new endpoint, r1c1 presents again within 5 s, its frame equal to the one-process
#     render of that frame; the job never connected to anything but the relay.
#  3. SIGSTOP of process 2 behind the relay: the others go on once the wall drops it, the relay's
#     memory stays bounded (within 64 MiB of before), and after SIGCONT it presents again.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
serve="" relay="" job="" restarted=""
layout=$1
cleanup() {
  for p in $job $relay $serve $restarted; do kill -9 "$p" 2>/dev/null || true; done
  pkill -9 -f "$work" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in serve.err relay.err job.err restarted.err; do echo "--- $f:"; tail -20 "$work/$f" 2>/dev/null || true; done
  exit 1
}
# now, since, latest, advanced, presentedSince, waitFor, pidOf, freePort
source "$(dirname "${BASH_SOURCE[0]}")/wall_watch.sh"

timeout=3
port=$(freePort) relayPort=$(freePort)
"$MPIEXEC" --enable-recovery --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -np 4 \
  "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" --offscreen --timeout $timeout \
  --capture-root "$work" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
# The relay reads the token file the wall created (the default one): it starts once the wall is up.
waitFor 20 grep -q "wall service on" "$work/serve.out" || fail "serve did not start"
"$DFBWALL" relay --listen "127.0.0.1:$relayPort" --wall "127.0.0.1:$port" --timeout $timeout \
  >"$work/relay.out" 2>"$work/relay.err" &
relay=$!
waitFor 5 grep -q "relay on" "$work/relay.out" || fail "the relay did not start"
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -np 2 "$DFBWALL" \
  --connect "127.0.0.1:$relayPort" --renderer pattern --frames 0 --quiet --timeout 30 \
  --capture "$work/cap" --capture-every 1 >"$work/job.out" 2>"$work/job.err" &
job=$!
waitFor 30 advanced 5 r0c0 r0c1 r1c0 r1c1 || fail "the job's frames did not reach the wall"
before=$(sed -n 's/.*wall process 3: pieces on \(tcp:[^ ]*\).*/\1/p' "$work/relay.err")
[ -n "$before" ] || fail "the relay named no piece socket for process 3"

# 1. kill -9 of wall process 3.
victim=$(pidOf 3)
[ -n "$victim" ] || fail "no wall process 3"
kill -9 "$victim"
waitFor $((timeout + 5)) grep -q "lost wall process 3" "$work/serve.err" || fail "process 3 was not dropped"
frame=$(latest r0c0)
waitFor 5 advanced "$frame" r0c0 r0c1 r1c0 || fail "the other displays did not present new frames"
kill -0 "$job" || fail "the job stopped when a wall process died"
waitFor 5 grep -q "lost wall process 3" "$work/job.err" || fail "the job was not told about the loss"
grep -q "roster .*lost wall process 3" "$work/relay.err" || fail "the relay did not pass the loss on"
dead=$(latest r1c1)

# 2. The documented restart of process 3: a new piece socket, which only the relay learns.
"$DFBWALL" serve --wall "$layout" --process 3 --join "127.0.0.1:$port" --offscreen \
  --timeout $timeout --capture-root "$work" >"$work/restarted.out" 2>"$work/restarted.err" &
restarted=$!
start=$(now)
waitFor 10 advanced "$dead" r1c1 || fail "the restarted process 3 presents nothing through the relay"
back=$(presentedSince "$start" "$dead" r1c1)
within "$back" 5 || fail "process 3 presented again only ${back} s after its restart"
grep -q "wall process 3 moved from tcp://127.0.0.1:[0-9]* to tcp://127.0.0.1:[0-9]*" "$work/relay.err" ||
  fail "the relay did not move its connection to the restarted process"
[ "$(sed -n 's/.*wall process 3: pieces on \(tcp:[^ ]*\).*/\1/p' "$work/relay.err")" = "$before" ] ||
  fail "the relay's own endpoint for process 3 changed"
frame=$(latest r1c1)
mkdir -p "$work/check/r1c1"
cp "$work/cap/r1c1/frame-$(printf %06d "$frame").png" "$work/check/r1c1/"
"$MPIEXEC" --oversubscribe -np 1 "$DFBWALL" --size "$("$COMPARE" --info "$layout" | cut -d' ' -f2)" \
  --renderer pattern --frames "$frame" --quiet --image "$work/full.png" || fail "the reference render failed"
"$COMPARE" "$layout" "$work/check" "$work/full.png" "$frame" r1c1 || fail "the rejoined display's frame $frame"
kill -0 "$job" || fail "the job stopped"

# 3. SIGSTOP of process 2: its pieces back up at the relay (which stops reading that process's
# socket once 16 batches wait for it) while the other displays keep presenting; after the wall
# drops it and SIGCONT, it rejoins. The relay's memory stays where it was.
rss() { awk '/^VmRSS/ {print $2}' "/proc/$relay/status"; }
rssBefore=$(rss)
stopped=$(pidOf 2)
[ -n "$stopped" ] || fail "no wall process 2"
kill -STOP "$stopped"
waitFor $((timeout + 5)) grep -q "lost wall process 2" "$work/serve.err" || { kill -CONT "$stopped"; fail "the stopped process 2 was not dropped"; }
frame=$(latest r0c0)
waitFor 5 advanced "$frame" r0c0 r0c1 r1c1 || { kill -CONT "$stopped"; fail "the others did not go on without process 2 behind the relay"; }
rssStopped=$(rss)
halted=$(latest r1c0)
kill -CONT "$stopped"
waitFor 10 grep -q "wall process 2 on .* is back in the wall" "$work/serve.err" ||
  fail "process 2 did not join again after SIGCONT"
halted=$(latest r1c0)
waitFor 10 advanced "$halted" r1c0 || fail "process 2 did not present again after SIGCONT"
[ "$rssStopped" -lt $((rssBefore + 65536)) ] ||
  fail "the relay grew from $rssBefore to $rssStopped KiB while process 2 was stopped"
kill -0 "$job" || fail "the job stopped"

kill -TERM "$job"
waitFor 20 sh -c "! kill -0 $job 2>/dev/null" || fail "the job did not stop on SIGTERM"
job=""
kill -USR1 "$relay"
wait "$relay" || fail "the relay exited non-zero after SIGUSR1"
relay=""
kill -USR1 "$serve"
waitFor 20 sh -c "! kill -0 $serve 2>/dev/null && ! kill -0 $restarted 2>/dev/null" || {
  ps -eo pid,stat,wchan:24,args | grep "[s]erve --wall $layout" | cut -c1-160
  fail "the wall (the restarted process 3 included) did not stop within 20 s of SIGUSR1"
}
serve="" restarted=""
echo "PASS: through the relay, kill -9 of process 3 left the others presenting; restarted, it presented frame $frame (equal to the one-process render) ${back} s after its start, the relay connected to its new socket; SIGSTOP of process 2: relay $rssBefore -> $rssStopped KiB"
