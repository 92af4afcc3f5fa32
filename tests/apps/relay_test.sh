#!/usr/bin/env bash
# `dfbwall relay` (README, "A wall that stays up"): render jobs connect to a relay instead of the
# wall. One `dfbwall serve` and one relay in front of it, on loopback:
#  - a 2-rank job through the relay (pattern, raw): its captures, written by the wall, equal the
#    one-process render; the relay's --stats line counts its batches;
#  - a stranger with the token sends the relay's piece socket a batch of a session the wall never
#    gave, a batch with no session and garbage, and its directory socket a message of the wall's
#    own link: the relay drops and logs them, the wall never sees them;
#  - the next job through the relay (scivis, 4 bricks, snappy) equals its one-process render, and
#    a job without the wall's token is refused at the relay's handshake, saying so;
#  - kill -9 of a job's rank: the relay closes the job's link to the wall, which drops the job at
#    once (its connection closed), not at its timeout;
#  - kill -9 of the relay during a job ends the job within its timeout, the wall drops it at once
#    (its connection closed), and a relay started again serves the next job;
#  - a relay whose wall does not answer refuses the job, saying so, within its timeout.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment, and /usr/bin/python3 with pyzmq.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
serve="" relay="" lonely="" long=""
cleanup() {
  for p in $long $lonely $relay $serve; do kill -9 "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  echo "--- serve:"; cat "$work/serve.out" "$work/serve.err" 2>/dev/null
  echo "--- relay:"; cat "$work/relay.out" "$work/relay.err" 2>/dev/null
  exit 1
}
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }
field() { grep -o "\"$2\": *[0-9.]*" "$1" | sed 's/.*: *//'; }

layout=$1
port=$((20000 + $$ % 20000)) relayPort=$((20000 + ($$ + 7) % 20000))
token=relaytesttoken
# The wall's deadline for a frame: the bricks job's first one (4 wavelet bricks built on 2 ranks)
# took over 5 s under the sanitizers and a loaded host.
wallTimeout=$((10 * ${DFBWALL_TIME_SCALE:-1}))
"$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  -np "$(processes "$layout")" "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" \
  --token "$token" --offscreen --timeout "$wallTimeout" --capture-root "$work" >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
"$DFBWALL" relay --listen "127.0.0.1:$relayPort" --wall "127.0.0.1:$port" --token "$token" --timeout 5 \
  --stats "$work/relay.jsonl" >"$work/relay.out" 2>"$work/relay.err" &
relay=$!
for _ in $(seq 100); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
grep -q "wall service on 127.0.0.1:$port" "$work/serve.out" || fail "serve did not start"
grep -qx "dfbwall: relay on 127.0.0.1:$relayPort for the wall at 127.0.0.1:$port" "$work/relay.out" ||
  fail "the relay did not start"

# job NAME FRAMES CODEC [dfbwall options]: 2 ranks through the relay, then the one-process render.
job() {
  local name=$1 frames=$2 codec=$3; shift 3
  mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$relayPort" --token "$token" --codec "$codec" \
    ${wait:-} --frames "$frames" --quiet --timeout 30 --capture "$work/$name" "$@" >"$work/$name.out" 2>&1 ||
    { cat "$work/$name.out"; fail "job $name through the relay failed"; }
  mpi -np 1 "$DFBWALL" --size "$(canvas "$layout")" --frames "$frames" --quiet \
    --image "$work/$name-full.png" "$@" || fail "reference of $name failed"
  "$COMPARE" "$layout" "$work/$name" "$work/$name-full.png" "$frames" || fail "job $name ($codec)"
}
job pattern 3 raw --renderer pattern
grep -q "wall process 3: pieces on tcp://127.0.0.1:" "$work/relay.err" || fail "no piece socket for process 3"
# The relay writes a job's line once the job has been gone a few seconds.
for _ in $(seq 100); do [ -s "$work/relay.jsonl" ] && break; sleep 0.1; done
[ "$(wc -l <"$work/relay.jsonl")" -eq 1 ] || fail "no --stats line for the first job"
batches=$(field "$work/relay.jsonl" batches_forwarded)
# 2 ranks x 4 displays x 3 frames: at least one batch each (a rank sends only its tiles' pieces).
[ "$batches" -ge 12 ] || fail "the relay forwarded $batches batches of 2 ranks x 4 displays x 3 frames"

# A stranger on the relay's piece socket of process 1: nothing reaches the wall.
endpoint=$(sed -n 's/.*wall process 1: pieces on \(tcp:[^ ]*\).*/\1/p' "$work/relay.err")
/usr/bin/python3 - "$endpoint" "tcp://127.0.0.1:$relayPort" "$token" <<'PY' || fail "the stranger could not send"
import struct, sys, time, zmq
ctx = zmq.Context()
def dealer(endpoint):  # past the relay's handshake: PLAIN, the token as the password
    s = ctx.socket(zmq.DEALER)
    s.setsockopt(zmq.LINGER, 2000)
    s.plain_username = b"dfbwall"
    s.plain_password = sys.argv[3].encode()
    s.connect(endpoint)
    return s
s = dealer(sys.argv[1])
def batch(session):  # header (magic, version 4, kind Batch), frame 1, display 1, rank 0, raw, 1 piece
    piece = struct.pack("<iiiiI", 0, 0, 4, 4, 64) + b"\xff" * 64
    return struct.pack("<IHHQ", 0x57424644, 4, 10, session) + struct.pack("<IiIII", 1, 1, 0, 0, 1) + piece
s.send(batch(0x5eed5eed5eed5eed))
s.send(batch(0))
s.send(b"not the protocol at all")
# On the relay's directory socket: a wall-link message (Join, kind 12) for the wall's head.
d = dealer(sys.argv[2])
d.send(struct.pack("<IHHQ", 0x57424644, 4, 12, 0) + b"\0" * 32)
time.sleep(1)
PY
for _ in $(seq 50); do grep -q "protocol" "$work/relay.err" && break; sleep 0.1; done
grep -q "dropped a message on the piece port from connection .*: not the session of a job" "$work/relay.err" ||
  fail "the relay did not log the stranger's batch"
grep -q "dropped a message on the piece port .*not the dfbwall protocol" "$work/relay.err" ||
  fail "the relay did not log the garbage"
grep -q "dropped message kind 12 from connection .*: not one a job sends" "$work/relay.err" ||
  fail "the relay did not drop the wall-link message"
if grep -q "dropped a message on the piece port\|kind 12" "$work/serve.err"; then
  fail "a stranger's message reached the wall"
fi

job bricks 2 snappy --renderer scivis --scene builtin:wavelet --bricks 4 --tile-size 32
if mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$relayPort" --token wrong --renderer pattern \
  --frames 1 --quiet --timeout 30 >"$work/wrong.out" 2>&1; then
  fail "a job with the wrong token was accepted through the relay"
fi
grep -q "refused the job at the handshake" "$work/wrong.out" || { cat "$work/wrong.out"; fail "no refusal"; }
for _ in $(seq 100); do [ "$(wc -l <"$work/relay.jsonl")" -ge 2 ] && break; sleep 0.1; done
[ "$(wc -l <"$work/relay.jsonl")" -eq 2 ] || fail "expected 2 --stats lines (accepted jobs only)"
strangers=$(tail -1 "$work/relay.jsonl" | grep -o '"strangers_dropped":[0-9]*' | cut -d: -f2)
[ "$strangers" -ge 3 ] || fail "the second job's line counts $strangers strangers' messages, not 3"

# kill -9 of a job's rank: mpirun ends the other, the job's connection to the relay closes, the
# relay closes the job's own link to the wall, and the wall drops the job at once.
mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$relayPort" --token "$token" --renderer pattern \
  --frames 0 --timeout 30 >"$work/killed.out" 2>&1 &
long=$!
for _ in $(seq 100); do grep -q '^frame [0-9]' "$work/killed.out" && break; sleep 0.1; done
grep -q '^frame [0-9]' "$work/killed.out" || { cat "$work/killed.out"; fail "the job to kill showed no frame"; }
rank=""
for p in $(pgrep -f -- "--connect 127.0.0.1:$relayPort --token $token --renderer pattern --frames 0 --timeout 30"); do
  [ "$(cat /proc/$p/comm)" = dfbwall ] && rank=$p
done
[ -n "$rank" ] || fail "no rank of the job to kill"
kill -9 "$rank"
# Within the wall's --timeout, and said so: a drop at the timeout would give its silence.
for _ in $(seq 50); do grep -q "ended after frame [0-9]* (its connection closed)" "$work/serve.err" && break; sleep 0.1; done
grep -q "dropping the job from .*: its connection closed" "$work/serve.err" ||
  fail "the wall did not drop the job behind the relay when its connection closed"
grep -q "its connection to the relay closed" "$work/relay.err" || fail "the relay did not say the job's connection closed"
wait "$long" 2>/dev/null || true
long=""

# kill -9 of the relay during a job is a cut link: the job ends within its timeout (5 s), the
# wall drops it, and a relay started again on the same port serves the next job (--wait).
mpi -np 2 "$DFBWALL" --connect "127.0.0.1:$relayPort" --token "$token" --renderer pattern \
  --frames 0 --timeout 5 >"$work/long.out" 2>&1 &
long=$!
for _ in $(seq 100); do grep -q '^frame [0-9]' "$work/long.out" && break; sleep 0.1; done
grep -q '^frame [0-9]' "$work/long.out" || { cat "$work/long.out"; fail "the long job showed no frame"; }
kill -9 "$relay"
wait "$relay" 2>/dev/null || true
t0=$(date +%s.%N)
if wait "$long"; then fail "the job went on without its relay"; fi
long=""
took=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
awk -v t="$took" 'BEGIN {exit !(t < 9)}' || fail "the job ended $took s after its relay died (timeout 5 s)"
"$DFBWALL" relay --listen "127.0.0.1:$relayPort" --wall "127.0.0.1:$port" --token "$token" --timeout 5 \
  >"$work/relay.out" 2>>"$work/relay.err" &
relay=$!
wait=--wait job again 2 raw --renderer pattern
[ "$(grep -c "dropping the job from .*: its connection closed" "$work/serve.err")" -ge 2 ] ||
  fail "the wall did not drop the orphaned job when the relay's connection closed"

# A relay whose wall does not answer tells the job so within its timeout (2 s here).
"$DFBWALL" relay --listen "127.0.0.1:$((relayPort + 1))" --wall "127.0.0.1:$((port + 1))" --token "$token" --timeout 2 \
  >"$work/lonely.out" 2>"$work/lonely.err" &
lonely=$!
if mpi -np 1 "$DFBWALL" --connect "127.0.0.1:$((relayPort + 1))" --token "$token" --renderer pattern --frames 1 \
  --quiet --timeout 30 >"$work/lonely-job.out" 2>&1; then
  fail "a job was accepted by a relay without a wall"
fi
grep -q "refused the job: relay: the wall at 127.0.0.1:$((port + 1)) did not answer within 2 s" \
  "$work/lonely-job.out" || { cat "$work/lonely-job.out"; fail "no 'did not answer' from the lonely relay"; }
kill -USR1 "$lonely"
wait "$lonely" || fail "the lonely relay exited non-zero after SIGUSR1"

kill -USR1 "$relay"
wait "$relay" || fail "the relay exited non-zero after SIGUSR1"
relay=""
kill -USR1 "$serve"
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""
echo "PASS: 3 jobs through the relay equal the one-process render ($batches batches in the first), a stranger's messages dropped at the relay, a wrong token refused through it, a job whose relay died ended in $took s"
