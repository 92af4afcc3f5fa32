#!/usr/bin/env bash
# Fault tests (label 'faults'): real ranks, real signals, real files. Each scenario asserts the
# exit code and how long the job took to end after the fault.
#   fault_test.sh throw RANK FRAME       DFBWALL_FAIL_AT=RANK:FRAME; gone within 3 s of the error
#   fault_test.sh sigstop                SIGSTOP of a wall rank; gone within --timeout + 3 s
#   fault_test.sh disk-full              captures into a full tmpfs; gone within 3 s
#   fault_test.sh signal SIG             SIG to mpirun: stats and captures whole, in 5 s
#   fault_test.sh window-close           a real GLFW window under Xvfb asked to close (as a
#                                        window manager does): graceful stop, exit 0, in 5 s
#   fault_test.sh stale-mesh             two render ranks whose mesh files differ (a stale copy on
#                                        one host): one error naming the scene, before any frame
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
    rank=$(tr '\0' '\n' <"/proc/$victim/environ" | sed -n 's/^OMPI_COMM_WORLD_RANK=//p')
    kill -STOP "$victim"
    stopped=$(now)
    ended=$(wait_end 20)
    code=$(exit_code)
    [ "$code" -ne 0 ] || fail "exit code 0"
    grep -q 'dfbwall: error on rank' "$work/log" || fail "no error message"
    # Whichever rank's deadline passes first, the cause names the stopped one.
    grep 'dfbwall: error on rank' "$work/log" | grep -q "not answering: rank $rank (" ||
      fail "the error does not name the stopped rank $rank as not answering"
    took=$(elapsed "$stopped" "$ended")
    awk -v t="$took" -v l=$((timeout + 3)) 'BEGIN {exit !(t <= l)}' ||
      fail "the job took ${took} s to end after SIGSTOP (limit: --timeout $timeout + 3 s)"
    echo "wall rank $rank (pid $victim) stopped: job gone ${took} s later (--timeout $timeout), exit $code"
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
  window-close)
    # Xvfb runs no window manager: close_window.py sends the WM_DELETE_WINDOW client message a
    # window manager's close button would.
    # Everything runs inside one xvfb-run.
    cat >"$work/inside.sh" <<'SH'
set -u
"$MPIEXEC" -n 6 --oversubscribe --bind-to none -x DISPLAY -x XAUTHORITY "$DFBWALL" \
  --wall "$LAYOUT" --renderer pattern --frames 100000000 --quiet --timeout 20 \
  --stats "$WORK/stats.jsonl" --capture "$WORK/cap" >"$WORK/log" 2>&1 &
job=$!
for ((i = 0; i < 600; i++)); do grep -q '"frame":' "$WORK/stats.jsonl" 2>/dev/null && break; sleep 0.05; done
sleep 1
date +%s.%N >"$WORK/sent"
"$CLOSE_WINDOW" r1c0 10 &
closer=$!
for ((i = 0; i < 100; i++)); do kill -0 $job 2>/dev/null || break; sleep 0.05; done
date +%s.%N >"$WORK/ended"
kill -0 $job 2>/dev/null && { kill -9 $job; exit 4; }
wait $closer || exit 3
wait $job
SH
    set +e
    WORK="$work" CLOSE_WINDOW="$(dirname "$0")/close_window.py" \
      xvfb-run -a -n $((300 + RANDOM % 500)) -s "-screen 0 1280x1024x24 -noreset" bash "$work/inside.sh"
    code=$?
    set -e
    [ "$code" -ne 3 ] || fail "no window titled r1c0 appeared"
    [ "$code" -ne 4 ] || fail "the job was still running 5 s after the window was closed"
    [ "$code" -eq 0 ] || fail "exit code $code after closing a window"
    took=$(elapsed "$(cat "$work/sent")" "$(cat "$work/ended")")
    grep -q "the window of display 'r1c0' was closed: stopping" "$work/log" || fail "no line naming the closed display"
    ! grep -q 'dfbwall: error' "$work/log" || fail "an error on a graceful stop"
    /usr/bin/python3 - "$work/stats.jsonl" <<'PY' || fail "statistics are not whole"
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
summary = [l["summary"] for l in lines if "summary" in l]
assert summary and summary[0]["stopped_early"] and summary[0]["exit_code"] == 0, summary
PY
    echo "window r1c0 closed: job gone ${took} s later, exit 0, statistics whole"
    ;;
  stale-mesh)
    # Two folders with the same scene text; the mesh one of them refers to is one vertex off,
    # as a stale copy on one host would be. Each render rank reads its own folder (MPMD).
    for host in a b; do
      mkdir -p "$work/$host"
      cat >"$work/$host/scene.toml" <<'TOML'
[camera]
position = [0, 0, 3]
look_at = [0, 0, 0]
[materials.white]
type = "diffuse"
color = [0.8, 0.8, 0.8]
[[meshes]]
name = "triangle"
material = "white"
file = "triangle.obj"
TOML
    done
    printf 'v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n' >"$work/a/triangle.obj"
    printf 'v -1 -1 0\nv 1 -1 0\nv 0 1.01 0\nf 1 2 3\n' >"$work/b/triangle.obj"
    common=(--size 64x64 --frames 2 --quiet --timeout 10)
    "$MPIEXEC" --oversubscribe --bind-to none -n 1 "$DFBWALL" --scene "$work/a/scene.toml" \
      "${common[@]}" : -n 1 "$DFBWALL" --scene "$work/b/scene.toml" "${common[@]}" \
      >"$work/log" 2>&1 &
    job=$!
    ended=$(wait_end 20)
    code=$(exit_code)
    [ "$code" -ne 0 ] || fail "exit code 0 with different meshes on the two ranks"
    grep -q "scene.toml: the render ranks read different bytes from this file or the files it refers to" \
      "$work/log" || fail "no error naming the scene"
    [ "$(grep -c 'different bytes' "$work/log")" -eq 1 ] || fail "expected the cause once"
    ! grep -q 'core dumped\|Segmentation fault' "$work/log" || fail "crash"
    # The same files on both ranks run.
    cp "$work/a/triangle.obj" "$work/b/triangle.obj"
    "$MPIEXEC" --oversubscribe --bind-to none -n 1 "$DFBWALL" --scene "$work/a/scene.toml" \
      "${common[@]}" : -n 1 "$DFBWALL" --scene "$work/b/scene.toml" "${common[@]}" \
      >"$work/log" 2>&1 || fail "identical copies refused"
    echo "a mesh differing between the render ranks is refused before any frame, exit $code"
    ;;
  *) echo "unknown scenario $scenario"; exit 2 ;;
esac
