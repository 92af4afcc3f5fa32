#!/usr/bin/env bash
# A keyboard on the wall: under Xvfb, real X key events (xdotool, through XTEST, into
# the focused window of a display) steer a running job: the right arrow orbits the camera
# (/api/status reports another camera) even while the converged wall idles, '+' dollies, Esc
# stops the job gracefully (exit 0, the statistics end with their summary).
#   keyboard_test.sh LAYOUT RENDER_RANKS     (DFBWALL, COMPARE, MPIEXEC in the environment)
set -euo pipefail
if [ -z "${KEYBOARD_TEST_INNER:-}" ]; then
  # A server number of its own, so a concurrent Xvfb test elsewhere cannot take the same one.
  exec xvfb-run -a -n $((300 + RANDOM % 500)) -s "-screen 0 1280x1024x24 -noreset" \
    env KEYBOARD_TEST_INNER=1 "$0" "$@"
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
layout=$1 renders=$2
w=$("$COMPARE" --info "$layout" | cut -d' ' -f1)
work=$(mktemp -d)
job=
cleanup() {
  [ -n "$job" ] && kill -0 "$job" 2>/dev/null && kill -TERM "$job" && sleep 2
  rm -rf "$work"
}
trap cleanup EXIT

# The control API's token, from the environment (never on a command line).
DFBWALL_CONTROL_TOKEN=$(od -An -N16 -tx1 /dev/urandom | tr -d ' \n')
export DFBWALL_CONTROL_TOKEN
auth="Authorization: Bearer $DFBWALL_CONTROL_TOKEN"
"$MPIEXEC" -n $((renders + w)) --oversubscribe --bind-to none -x DISPLAY -x XAUTHORITY \
  "$DFBWALL" --wall "$layout" --renderer primary --frames 0 --max-spp 4 --control 127.0.0.1:0 \
  --stats "$work/stats.json" --quiet >"$work/out.txt" 2>&1 &
job=$!

status() { curl -sf -H "$auth" "$base/api/status"; }
camera() { status | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["camera"])'; }
# wait_until SECONDS WHAT COMMAND...: polls COMMAND until it succeeds.
wait_until() {
  local seconds=$1 what=$2; shift 2
  for _ in $(seq $((seconds * 10))); do
    "$@" && return 0
    kill -0 "$job" 2>/dev/null || { echo "FAIL: the job ended waiting for $what"; cat "$work/out.txt"; exit 1; }
    sleep 0.1
  done
  echo "FAIL: $what: not within $seconds s"; cat "$work/out.txt"; exit 1
}

wait_until 90 "the control address" grep -q "control API on http://" "$work/out.txt"
base=$(grep -o 'http://[0-9.]*:[0-9]*' "$work/out.txt" | head -n1)
wait_until 60 "the first frames" sh -c "curl -sf -H '$auth' '$base/api/status' | grep -q '\"frame\": *[2-9]\|\"frame\": *[1-9][0-9]'"
# The first display's window, by its title (the display's name).
name=$(/usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["displays"][0]["name"])' < <(curl -sf -H "$auth" "$base/api/layout"))
window=$(xdotool search --sync --name "^$name\$" | head -n1)
xdotool windowfocus --sync "$window"

# Converged (4 samples per pixel): the renderers idle, the wall waits, and still hears its keys.
wait_until 60 "the idle, converged wall" sh -c "curl -sf -H '$auth' '$base/api/status' | grep -q '\"idle\": *true'"
before=$(camera)
xdotool key --delay 100 Right Right
wait_until 20 "a new camera after the right arrow" sh -c "[ \"\$(curl -sf -H '$auth' '$base/api/status' | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)[\"camera\"])')\" != \"$before\" ]"
orbited=$(camera)
echo "right arrow: camera $before -> $orbited"
xdotool key --delay 100 plus
wait_until 20 "a new camera after '+'" sh -c "[ \"\$(curl -sf -H '$auth' '$base/api/status' | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)[\"camera\"])')\" != \"$orbited\" ]"
echo "plus: camera $(camera)"

xdotool key Escape
for _ in $(seq 300); do kill -0 "$job" 2>/dev/null || break; sleep 0.1; done
kill -0 "$job" 2>/dev/null && { echo "FAIL: Esc did not stop the job within 30 s"; cat "$work/out.txt"; exit 1; }
code=0; wait "$job" || code=$?
job=
[ "$code" -eq 0 ] || { echo "FAIL: exit $code after Esc"; cat "$work/out.txt"; exit 1; }
tail -n 1 "$work/stats.json" | grep -q '^{"summary":' || { echo "FAIL: no summary in the statistics"; exit 1; }
grep -q "Esc pressed" "$work/out.txt" || { echo "FAIL: no word of the Esc"; cat "$work/out.txt"; exit 1; }
echo "Esc: the job stopped gracefully, exit 0, statistics complete"
