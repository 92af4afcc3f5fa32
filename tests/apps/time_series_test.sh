#!/usr/bin/env bash
# A volume time series on the wall (docs/scivis.md, "Time series"):
#  - 6 steps of a small NRRD series (step-%02d.nrrd, one step a frame) play on an offscreen 2x2
#    wall with --bricks 4 on 3 render ranks: every frame's captures equal a one-process render
#    of that step alone (its own scene file naming the one file), byte for byte;
#  - the same series named by a glob plays the same frames; image-parallel on 2 ranks too;
#  - the control API pauses and seeks it (the status shows the step, the picture converges) and
#    refuses a seek past its end;
#  - a missing step and a step whose dims differ: one error naming the step's file, every rank
#    exits non-zero, no hang.
#   time_series_test.sh LAYOUT
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
series="/usr/bin/python3 $(cd "$(dirname "$0")/../.." && pwd)/scripts/write_series.py"
work=$(mktemp -d)
job=""
cleanup() {
  # mpirun and its ranks (killed alone it would leave them running).
  [ -z "$job" ] || kill -9 $(pgrep -P "$job") "$job" 2>/dev/null || true
  [ -n "${KEEP:-}" ] || rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
mpi() { local n=$1; shift; "$MPIEXEC" -n "$n" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }

layout=$1
walls=$(processes "$layout")
size=$(canvas "$layout")
steps=6
mkdir -p "$work/good" "$work/bad"
$series "$work/good" $steps 24 20 16

# scene FILE VOLUME_FIELDS: a scene of one series volume, its isosurface and a light.
scene() {
  cat >"$1" <<TOML
[camera]
position = [2.2, 1.4, 2.6]
look_at = [0, 0, 0]
fov = 40

[materials.skin]
type = "diffuse"
color = [0.9, 0.7, 0.4]

[[volumes]]
name = "blob"
source = "file"
spacing = 0.08
origin = [-0.92, -0.76, -0.6]
$2
transfer_function = { preset = "viridis", range = [0.0, 160.0], opacity = [[0, 0], [60, 0.02], [160, 0.3]] }

[[isosurfaces]]
volume = "blob"
value = 70.0
material = "skin"
TOML
}
scene "$work/good/series.toml" $'file = "step-%02d.nrrd"\ntime_steps = 6'
scene "$work/good/glob.toml" $'file = "step-*.nrrd"'
common=(--renderer scivis --spp 1 --seed 7 --quiet --timeout 60)

# The series on the wall: frame k+1 shows step k.
mpi $((3 + walls)) "$DFBWALL" --wall "$layout" --offscreen --scene "$work/good/series.toml" \
  --bricks 4 --frames $steps --capture "$work/cap" --capture-every 1 --stats "$work/stats.json" "${common[@]}" ||
  fail "the series did not play"
for k in $(seq 0 $((steps - 1))); do
  scene "$work/good/step-$k.toml" "file = \"step-0$k.nrrd\""
  mpi 1 "$DFBWALL" --scene "$work/good/step-$k.toml" --size "$size" --frames 1 \
    --image "$work/ref-$k.png" "${common[@]}" || fail "the one-process render of step $k"
  "$COMPARE" "$layout" "$work/cap" "$work/ref-$k.png" $((k + 1)) ||
    fail "wall frame $((k + 1)) is not step $k's one-process render"
done
# Each step differs from the one before (else the comparison above proves nothing).
for k in $(seq 1 $((steps - 1))); do
  if cmp -s "$work/ref-$((k - 1)).png" "$work/ref-$k.png"; then fail "steps $((k - 1)) and $k look alike"; fi
done
shown=$(grep -o '"time_step":[0-9]*' "$work/stats.json" | cut -d: -f2 | tr '\n' ' ')
[ "$shown" = "0 1 2 3 4 5 " ] || fail "the frames showed steps '$shown', expected 0 to 5"
[ "$(grep -c '"step":{"read_ms"' "$work/stats.json")" -eq $((steps - 1)) ] ||
  fail "the statistics lack the read, build and wait times of each step switched to"

# A glob names the same steps in name order: the same wall frames.
mpi $((3 + walls)) "$DFBWALL" --wall "$layout" --offscreen --scene "$work/good/glob.toml" \
  --bricks 4 --frames 3 --capture "$work/glob" --capture-every 1 "${common[@]}" || fail "the glob series did not play"
for k in 0 1 2; do
  "$COMPARE" "$layout" "$work/glob" "$work/ref-$k.png" $((k + 1)) || fail "glob frame $((k + 1))"
done

# Image-parallel (no --bricks), 2 ranks: each rank builds the whole scene of the next step on
# its prefetch thread; frame 3 is step 2.
mpi 2 "$DFBWALL" --scene "$work/good/series.toml" --size "$size" --frames 3 \
  --image "$work/image-parallel.png" "${common[@]}" || fail "the series image-parallel"
cmp -s "$work/image-parallel.png" "$work/ref-2.png" ||
  fail "image-parallel frame 3 is not step 2's one-process render"

# Steering the series through the control API: pause, seek, the status' time, bad requests.
port=$((20000 + $$ % 20000))
token=series-test-token-0123456789
(umask 077 && echo "$token" >"$work/token")
"$MPIEXEC" -n $((3 + walls)) --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 \
  "$DFBWALL" --wall "$layout" --offscreen --scene "$work/good/series.toml" --bricks 4 \
  --frames 0 --max-spp 1 --control "127.0.0.1:$port" --control-token-file "$work/token" \
  "${common[@]}" >"$work/control.out" 2>&1 &
job=$!
api() { curl -s -o "$work/reply" -w '%{http_code}' -H "Authorization: Bearer $token" "$@"; }
status() { api "http://127.0.0.1:$port/api/status" >/dev/null; cat "$work/reply"; }
# The control port answers before the scene is read; the series is known once the status says so.
for _ in $(seq 300); do status | grep -q '"time":{' && break; sleep 0.1; done
[ "$(api -d '{"play": false}' "http://127.0.0.1:$port/api/time")" = 200 ] || fail "pause: $(cat "$work/reply")"
[ "$(api -d '{"seek": 4}' "http://127.0.0.1:$port/api/time")" = 200 ] || fail "seek: $(cat "$work/reply")"
for _ in $(seq 300); do
  status | grep -q '"idle":true' && status | grep -q '"time":{"step":4,"steps":6,"playing":false}' && break
  sleep 0.1
done
status | grep -q '"time":{"step":4,"steps":6,"playing":false}' || fail "the status after a seek: $(status)"
status | grep -q '"idle":true' || fail "paused, the series did not converge: $(status)"
[ "$(api -d '{"seek": 6}' "http://127.0.0.1:$port/api/time")" = 400 ] || fail "a seek past the series was taken"
grep -q "past the series' 6 steps" "$work/reply" || fail "the refused seek says: $(cat "$work/reply")"
[ "$(api -d '{"play": 1}' "http://127.0.0.1:$port/api/time")" = 400 ] || fail "play 1 was taken"
[ "$(api -X POST "http://127.0.0.1:$port/api/stop")" = 200 ] || fail "stop"
wait "$job" || { cat "$work/control.out"; fail "the steered series did not stop with exit 0"; }
job=""

# fails WHAT TEXT SCENE: every rank exits non-zero within the timeout, one error naming TEXT.
fails() {
  local what=$1 text=$2 sceneFile=$3 output code
  set +e
  output=$(timeout 60 "$MPIEXEC" -n 3 --oversubscribe --bind-to none "$DFBWALL" \
    --scene "$sceneFile" --bricks 4 --frames 2 --size 160x120 "${common[@]}" 2>&1)
  code=$?
  set -e
  [ "$code" -ne 0 ] || fail "$what: exit code 0"
  [ "$code" -ne 124 ] || fail "$what: hung"
  grep -qF -- "$text" <<<"$output" || { echo "$output"; fail "$what: the message lacks '$text'"; }
  [ "$(grep -c 'dfbwall: error' <<<"$output")" -eq 1 ] || { echo "$output"; fail "$what: not one error line"; }
  if grep -q 'core dumped\|Segmentation\|Aborted' <<<"$output"; then fail "$what: crashed"; fi
}
scene "$work/good/missing.toml" $'file = "step-%02d.nrrd"\ntime_steps = 7'
fails "a missing step" "volume 'blob'.file: time step 6 ($work/good/step-06.nrrd)" "$work/good/missing.toml"
$series "$work/bad" 4 24 20 16 --bad-dims 2
scene "$work/bad/series.toml" $'file = "step-%02d.nrrd"\ntime_steps = 4'
fails "a step of other dims" \
  "time step 2 ($work/bad/step-02.nrrd) is 25x20x16 float32, the first step ($work/bad/step-00.nrrd) 24x20x16 float32" \
  "$work/bad/series.toml"
echo "PASS: $steps steps on the wall (--bricks 4, 3 render ranks) equal each step's one-process render; a glob and image-parallel play the same; pause and seek through the API; a missing step and changed dims are one named error"
