#!/usr/bin/env bash
# Fault tests (label 'faults'): real ranks, real signals, real files. Each scenario asserts the
# exit code and how long the job took to end after the fault.
#   fault_test.sh throw RANK FRAME       DFBWALL_FAIL_AT=RANK:FRAME; gone within 3 s of the error
#   fault_test.sh sigstop                SIGSTOP of a wall rank; gone within --timeout + 3 s
#   fault_test.sh disk-full              captures into a full tmpfs; gone within 3 s
#   fault_test.sh signal SIG             SIG to mpirun: stats and captures whole, in 5 s
# Needs DFBWALL, MPIEXEC and LAYOUT (a 2x2 layout) in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d)
job=""
cleanup() {
  if [ -n "$job" ] && kill -0 "$job" 2>/dev/null; then
    pkill -CONT -P "$job" 2>/dev/null || true
    kill -9 "$job" 2>/dev/null || true
  fi
  if mountpoint -q "$work/full" 2>/dev/null; then umount "$work/full"; fi
  rm -rf "$work"
}
trap cleanup EXIT
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.2f", b - a}'; }
fail() { echo "FAIL: $*"; echo "--- output"; cat "$work/log" 2>/dev/null || true; exit 1; }

# Starts a 6-rank pattern wall in the background that would run for hours.
start() {
  "$MPIEXEC" -n 6 --oversubscribe --bind-to none "$DFBWALL" --wall "$LAYOUT" --offscreen \
    --renderer pattern --frames 100000000 --quiet "$@" >"$work/log" 2>&1 &
  job=$!
}
# Waits up to $1 seconds for the job to end; prints the time it ended; sets $code.
wait_end() {
  local limit=$1 i
  for ((i = 0; i < limit * 20; i++)); do kill -0 "$job" 2>/dev/null || break; sleep 0.05; done
  kill -0 "$job" 2>/dev/null && fail "the job is still running ${limit} s later"
  now
}
# Waits for a line matching $1 in the log; prints the time it appeared.
wait_line() {
  local i
  for ((i = 0; i < 600; i++)); do grep -q -- "$1" "$work/log" && { now; return; }; sleep 0.05; done
  fail "no line matching '$1' within 30 s"
}
# Waits (up to 30 s: start-up is slow on a loaded machine) until frames flow: a frame line in
# the statistics file $1.
wait_running() {
  local i
  for ((i = 0; i < 600; i++)); do grep -q '"frame":' "$1" 2>/dev/null && return; sleep 0.05; done
  fail "no frame in the statistics within 30 s"
}
# The job's exit code, once it ended.
exit_code() { set +e; wait "$job"; local c=$?; set -e; job=""; echo "$c"; }
# Exactly one cause, naming rank and host, and no crash.
one_cause() {
  [ "$(grep -c 'dfbwall: error on rank' "$work/log")" -eq 1 ] || fail "expected exactly one error line"
  grep -q -- "$1" "$work/log" || fail "the error does not name '$1'"
  ! grep -q 'core dumped\|Segmentation fault\|messaging did not quiesce' "$work/log" || fail "crash or noise"
}

scenario=$1; shift
case "$scenario" in
  throw)
    rank=$1 frame=$2
    DFBWALL_FAIL_AT="$rank:$frame" start --timeout 20
    seen=$(wait_line 'dfbwall: error on rank')
    ended=$(wait_end 10)
    code=$(exit_code)
    [ "$code" -ne 0 ] || fail "exit code 0"
    one_cause "rank $rank (.*): injected failure at frame $frame"
    took=$(elapsed "$seen" "$ended")
    awk -v t="$took" 'BEGIN {exit !(t <= 3)}' || fail "the job took ${took} s to end after the error"
    echo "error on rank $rank at frame $frame: job gone ${took} s after the message, exit $code"
    ;;
  sigstop)
    timeout=2
    start --timeout "$timeout" --stats "$work/stats.jsonl"
    wait_running "$work/stats.jsonl"
    victim=$(pgrep -P "$job" -x dfbwall | sort -n | tail -n 1 || true)
    [ -n "$victim" ] || fail "no rank to stop"
    kill -STOP "$victim"
    stopped=$(now)
    ended=$(wait_end 20)
    code=$(exit_code)
    [ "$code" -ne 0 ] || fail "exit code 0"
    grep -q 'dfbwall: error on rank' "$work/log" || fail "no error message"
    took=$(elapsed "$stopped" "$ended")
    awk -v t="$took" -v l=$((timeout + 3)) 'BEGIN {exit !(t <= l)}' ||
      fail "the job took ${took} s to end after SIGSTOP (limit: --timeout $timeout + 3 s)"
    echo "wall rank $victim stopped: job gone ${took} s later (--timeout $timeout), exit $code"
    grep 'dfbwall: error' "$work/log"
    ;;
  disk-full)
    mkdir "$work/full"
    if ! mount -t tmpfs -o size=256k tmpfs "$work/full" 2>/dev/null; then
      echo "SKIP: cannot mount a tmpfs here (needs root): the full-disk case is not tested"
      exit 77
    fi
    start --timeout 20 --capture "$work/full/cap" --capture-every 1
    seen=$(wait_line 'dfbwall: error on rank')
    ended=$(wait_end 10)
    code=$(exit_code)
    [ "$code" -ne 0 ] || fail "exit code 0"
    one_cause "No space left on device"
    took=$(elapsed "$seen" "$ended")
    awk -v t="$took" 'BEGIN {exit !(t <= 3)}' || fail "the job took ${took} s to end after the error"
    # Nothing half-written under a final name: every capture decodes (the temporaries are
    # hidden and removed).
    [ -z "$(find "$work/full/cap" -name '.*.png.*')" ] || fail "temporary files left behind"
    echo "disk full: job gone ${took} s after the message, exit $code, no temporaries left"
    ;;
  signal)
    sig=$1
    start --timeout 20 --stats "$work/stats.jsonl" --capture "$work/cap"
    wait_running "$work/stats.jsonl"
    sleep 1
    sent=$(now)
    kill "-$sig" "$job"
    ended=$(wait_end 5)
    code=$(exit_code)
    took=$(elapsed "$sent" "$ended")
    # mpirun exits 1 after Ctrl-C/SIGTERM whatever the ranks do; SIGUSR1 is the clean stop.
    if [ "$sig" = USR1 ]; then [ "$code" -eq 0 ] || fail "exit code $code after SIGUSR1"; fi
    /usr/bin/python3 - "$work/stats.jsonl" <<'PY' || fail "statistics are not whole"
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]   # every line parses
frames = [l for l in lines if "frame" in l]
summary = [l["summary"] for l in lines if "summary" in l]
assert frames, "no frame lines"
assert summary and summary[0]["stopped_early"], "no summary saying the run stopped early"
assert summary[0]["frames"] == len(frames), (summary[0]["frames"], len(frames))
print(f"{len(frames)} frames streamed, summary: {summary[0]['frames']} frames, "
      f"exit code {summary[0]['exit_code']}")
PY
    last=$(grep -o '"frame":[0-9]*' "$work/stats.jsonl" | tail -n 1 | cut -d: -f2)
    name=$(printf 'frame-%06d.png' "$last")
    for d in r0c0 r0c1 r1c0 r1c1; do
      [ -f "$work/cap/$d/$name" ] || fail "no capture $d/$name of the last frame"
    done
    [ -f "$work/cap/$(printf 'wall-%06d.png' "$last")" ] || fail "no wall preview of the last frame"
    [ -z "$(find "$work/cap" -name '.*')" ] || fail "temporary files left behind"
    ! grep -q 'dfbwall: error' "$work/log" || fail "an error on a graceful stop"
    echo "SIG$sig: job gone ${took} s later, exit $code, last frame $last captured on every display"
    ;;
  *) echo "unknown scenario $scenario"; exit 2 ;;
esac
