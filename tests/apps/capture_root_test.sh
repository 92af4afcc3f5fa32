#!/usr/bin/env bash
# Captures stay in their folder (docs/security.md, "Captures stay in their folder"), tried as an
# attacker would on one host: a real `dfbwall serve` (umask 027, --capture-root, a small
# --capture-quota) on a layout of two wall processes, and real jobs on loopback.
#  - --capture ../x, an absolute path elsewhere, a folder through a link inside the root that
#    points out: each refused with a message naming the root; nothing created outside the root.
#  - a folder one member cannot use refuses the job, and the head made nothing for it either.
#  - a link planted at an image's own name: the job ends with the reason; the link and the file
#    it points to are untouched.
#  - a job that captures every frame ends when it would pass the quota, saying so; no wall
#    process wrote more than the quota.
#  - then a good job's captures equal the one-process render, files 0640 and folders 0750.
#  - a second wall (one process, umask 077): a good job's files are 0600, folders 0700.
#  - a wall without --capture-root refuses a job's captures with the hint naming the option; a
#    --stats that is a link refuses to start the wall.
# Needs DFBWALL, COMPARE and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
serve="" alone=""
elsewhere="/tmp/dfbwall-capture-elsewhere-$$"
cleanup() {
  for p in $serve $alone; do kill -9 "$p" 2>/dev/null || true; done
  pkill -9 -f "$work" 2>/dev/null || true
  rm -rf "$work" "$elsewhere"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in serve.err alone.err; do echo "--- $f:"; tail -20 "$work/$f" 2>/dev/null || true; done
  exit 1
}
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
# now, since, latest, advanced, presentedSince, waitFor, pidOf, freePort
source "$(dirname "${BASH_SOURCE[0]}")/wall_watch.sh"
mode() { stat -c %a "$1"; }

layout=$1 small=$2
root="$work/root" outside="$work/outside"
mkdir -p "$root" "$outside"
echo precious >"$outside/victim"
quota=200000
port=$(freePort)
(umask 027 && exec "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 -np 2 \
  "$DFBWALL" serve --wall "$layout" --listen "127.0.0.1:$port" --offscreen --timeout 5 \
  --capture-root "$root" --capture-quota $quota >"$work/serve.out" 2>"$work/serve.err") &
serve=$!
waitFor 20 grep -q "wall service on" "$work/serve.out" || fail "serve did not start"

# job NAME CAPTURE [options]: a one-rank pattern job; its output in $work/NAME.out, its status in
# $status.
job() {
  local name=$1 capture=$2; shift 2
  status=0
  timeout 60 "$MPIEXEC" --oversubscribe --bind-to none -np 1 "$DFBWALL" \
    --connect "127.0.0.1:$port" --renderer pattern --quiet --timeout 30 ${capture:+--capture "$capture"} "$@" \
    >"$work/$name.out" 2>&1 || status=$?
}
# refused NAME TEXT: the job failed (not by the timeout) and said TEXT.
refused() {
  [ "$status" -ne 0 ] && [ "$status" -ne 124 ] || fail "job $1: exit $status, expected a refusal"
  grep -qF -- "$2" "$work/$1.out" || { cat "$work/$1.out"; fail "job $1 does not say: $2"; }
  echo "job $1 refused: $(grep -m1 -oF -- "$2" "$work/$1.out")"
}
beneath="beneath the capture root $root"

job dotdot ../x --frames 1
refused dotdot "'../x': '..' is not allowed $beneath"
[ ! -e "$work/x" ] || fail "../x was created"

job absolute "$elsewhere" --frames 1
refused absolute "'$elsewhere': outside the capture root $root"
[ ! -e "$elsewhere" ] || fail "$elsewhere was created"

ln -s "$outside" "$root/out"
job link out/job --frames 1
refused link "'out/job': 'out' is a symbolic link, and none is followed $beneath"

# A member (process 1, display 'right') cannot use its folder: the job is refused, and the head
# made nothing for it either (nothing is made before every process accepted the job).
mkdir -p "$root/blocked" && touch "$root/blocked/right"
job blocked blocked --frames 1
refused blocked "capture folder on wall process 1: 'blocked/right': 'blocked/right' is not a folder"
[ "$(ls "$root/blocked")" = right ] || fail "a refused job's folders were made: $(ls "$root/blocked")"

# A link planted at the name of the image the job's last frame will have.
mkdir -p "$root/planted/left"
ln -s "$outside/victim" "$root/planted/left/frame-000002.png"
job planted planted --frames 2
refused planted "planted/left/frame-000002.png: is a symbolic link; outputs never follow or replace one"
[ -L "$root/planted/left/frame-000002.png" ] || fail "the planted link was replaced"
[ "$(cat "$outside/victim")" = precious ] || fail "the file the link points to changed"
[ "$(ls "$outside")" = victim ] || fail "something was created outside the root: $(ls "$outside")"

# Every frame captured, until stopped: only the quota ends it.
job quota quota --frames 0 --capture-every 1
refused quota "not written: the job's captures would pass the capture quota of"
refused quota "on this wall process (serve --capture-quota)"
head=$(cat "$root"/quota/left/*.png "$root"/quota/wall-*.png 2>/dev/null | wc -c)
member=$(cat "$root"/quota/right/*.png 2>/dev/null | wc -c)
[ "$head" -le $quota ] && [ "$member" -le $quota ] ||
  fail "the processes wrote $head and $member bytes for a quota of $quota"
[ "$member" -gt 0 ] || fail "the quota job captured nothing on the member"
[ -z "$(find "$root/quota" -name '.*')" ] || fail "temporaries left: $(find "$root/quota" -name '.*')"
echo "quota job ended: the head wrote $head bytes, the member $member, quota $quota"

# After all that, a good job: its captures equal the one-process render.
kill -0 "$serve" || fail "the wall died"
job good good/run --frames 2 --codec raw
[ "$status" -eq 0 ] || { cat "$work/good.out"; fail "the good job failed (exit $status)"; }
mpi -np 1 "$DFBWALL" --size "$("$COMPARE" --info "$layout" | cut -d' ' -f2)" --renderer pattern \
  --frames 2 --quiet --image "$work/full.png" || fail "the one-process render failed"
"$COMPARE" "$layout" "$root/good/run" "$work/full.png" 2 || fail "the good job's captures differ"
[ "$(mode "$root/good/run/left/frame-000002.png")" = 640 ] &&
  [ "$(mode "$root/good/run/right/frame-000002.png")" = 640 ] &&
  [ "$(mode "$root/good/run/wall-000002.png")" = 640 ] || fail "capture modes under umask 027: $(
    stat -c '%a %n' "$root"/good/run/*/*.png "$root"/good/run/*.png)"
[ "$(mode "$root/good")" = 750 ] && [ "$(mode "$root/good/run/right")" = 750 ] ||
  fail "folder modes under umask 027: $(stat -c '%a %n' "$root/good" "$root"/good/run/*/)"
echo "good job: captures equal the one-process render; files 640, folders 750 under umask 027"
kill -USR1 "$serve"
wait "$serve" || fail "serve exited non-zero after SIGUSR1"
serve=""

# alone NAME [serve options]: one wall process of the one-display layout, umask 077.
alone() {
  local name=$1; shift
  aport=$(freePort)
  (umask 077 && exec "$DFBWALL" serve --wall "$small" --process 0 --listen "127.0.0.1:$aport" \
    --offscreen --timeout 5 "$@" >"$work/$name.out" 2>"$work/alone.err") &
  alone=$!
  waitFor 20 grep -q "wall service on" "$work/$name.out" || fail "serve ($name) did not start"
}
stop_alone() { kill -USR1 "$alone"; wait "$alone" || fail "serve exited non-zero"; alone=""; }

mkdir -p "$work/root77"
alone root77 --capture-root "$work/root77"
port=$aport
job strict strict --frames 1
[ "$status" -eq 0 ] || { cat "$work/strict.out"; fail "the job on the umask 077 wall failed"; }
[ "$(mode "$work/root77/strict/main/frame-000001.png")" = 600 ] &&
  [ "$(mode "$work/root77/strict/main")" = 700 ] ||
  fail "modes under umask 077: $(stat -c '%a %n' "$work/root77/strict/main" "$work"/root77/strict/main/*)"
echo "umask 077: files 600, folders 700"
stop_alone

alone noroot
port=$aport
job noroot "$work/anywhere" --frames 1
refused noroot "this wall writes no captures for jobs; its operator allows them beneath a folder with serve --capture-root DIR"
[ ! -e "$work/anywhere" ] || fail "a wall without a capture root made the job's folder"
job nocapture "" --frames 1
[ "$status" -eq 0 ] || { cat "$work/nocapture.out"; fail "a job without captures failed there"; }
stop_alone

ln -s "$outside/victim" "$work/stats-link"
status=0
"$DFBWALL" serve --wall "$small" --process 0 --listen 127.0.0.1:0 --offscreen \
  --stats "$work/stats-link" >"$work/stats.out" 2>&1 || status=$?
[ "$status" -eq 1 ] && grep -qF "stats-link: is a symbolic link; outputs never follow one" "$work/stats.out" ||
  { cat "$work/stats.out"; fail "serve --stats through a link: exit $status"; }
[ "$(cat "$outside/victim")" = precious ] || fail "--stats wrote through the link"
echo "PASS: 6 attacks refused with nothing written outside the root; quota held; good jobs right"
