#!/usr/bin/env bash
# The command line tells the truth, for each command (the render job, serve, relay, show and the
# dfbwall-layout helper):
#  - its --help lists exactly the options it reads, in its groups (the lists below);
#  - an option of another command is refused: one message naming the option and the command,
#    exit 2, nothing started (no image, no wall, no relay);
#  - a good command line still runs: a --dry-run, an image, and a job and a picture through a
#    relay to a wall that serve runs, each command with every group's options it can take here.
# Needs DFBWALL, DFBWALL_LAYOUT (dfbwall-layout) and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
layout="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/configs/walls/1x1.toml"
work=$(mktemp -d)
serve="" relay=""
cleanup() {
  for p in $relay $serve; do kill -9 "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in "$work"/*.out "$work"/*.err; do
    case $f in */refused-*) continue ;; esac  # a failing refusal's message quotes its own
    [ -s "$f" ] && { echo "--- $f:"; cat "$f"; }
  done
  exit 1
}
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
waitFor() {  # waitFor SECONDS COMMAND...: true once COMMAND succeeds
  local tries=$(($1 * 10)); shift
  for _ in $(seq "$tries"); do "$@" && return 0; sleep 0.1; done
  return 1
}

# What each command reads (follow each option's field to its use), group by group, in order.
render_job='Scene: --scene --camera-path --orbit
Rendering: --renderer --size --spp --frames --seed --max-depth --exposure --filmic --tile-size --threads --distribution
Data-parallel scivis (bricks): --bricks --replication --ghost
Wall: --wall --offscreen --mode --dry-run
Connect to a wall service: --connect --token-file --token --server-key --codec --wait --window
Control: --control --control-token-file --control-host --max-spp
Throughput: --frames-in-flight --handler-threads --no-compress --compress-within-host
Failure handling: --timeout --memory-limit
Output: --view --image --capture --capture-every --preview --stats --quiet
Help: --help
Subcommands: serve relay show'
serve_command='Wall: --wall --offscreen --max-jobs
Network and security: --listen --process --join --advertise --token-file --token --server-key --curve
Throughput: --frames-in-flight --handler-threads
Failure handling: --timeout
Output: --stats --capture-root --capture-quota --capture --capture-every --background
Control: --control --control-token-file --control-host --thumbnail-size
Help: --help'
relay_command='Network: --listen --wall --token-file --token --server-key --curve
Failure handling: --timeout
Output: --stats
Help: --help'
show_command='Positionals:
Pictures: --fps --loop --once --filter --background
Connect to a wall service: --connect --token-file --token --server-key --codec --wait --window
Failure handling: --timeout --memory-limit
Output: --capture --capture-every --stats --quiet
Help: --help'

# groups HELP_TEXT: "Group: --option ..." per group, as --help lists them (subcommands too).
groups() {
  awk '/^[A-Z][A-Za-z ()-]*:$/ { if (line != "") print line; line = $0; sub_ = $0 == "Subcommands:"; next }
       line == "" { next }
       /^  -/ { n = split($1, names, ","); name = names[n]; sub(/[^a-z-].*$/, "", name)
                line = line " " name; next }
       /^  [a-z]/ && sub_ { line = line " " $1 }
       END { if (line != "") print line }' <<<"$1"
}

# 1. --help: exactly the expected options, in their groups; exit 0.
for command in render_job serve_command relay_command show_command; do
  case $command in
    render_job) args=() ;;
    serve_command) args=(serve) ;;
    relay_command) args=(relay) ;;
    show_command) args=(show) ;;
  esac
  help=$("$DFBWALL" ${args[@]+"${args[@]}"} --help) || fail "dfbwall ${args[*]} --help exited non-zero"
  listed=$(groups "$help")
  [ "$listed" = "${!command}" ] || fail "dfbwall ${args[*]} --help lists
$listed
expected
${!command}"
done
echo "--help: the render job, serve, relay and show list exactly their options, in their groups"

# options LIST: the options of a command's list, one a line.
options() { sed 's/^[^:]*://' <<<"$1" | tr ' ' '\n' | grep '^--' | grep -vx -- --help; }
# takes LIST OPTION: whether the list has OPTION (in bash alone: it is asked ~300 times).
takes() {
  local words=" ${1//$'\n'/ } "
  [[ $words == *" $2 "* ]]
}

# 2. An option another command takes is refused: the message names it and the command, exit 2.
# refused NAME EXPECTED_PREFIX ARGS...: queues dfbwall ARGS, which must fail saying EXPECTED_PREFIX.
# The ~140 cases are process starts: check_refusals runs them a few at a time, then checks each.
refusals=0
refused() {
  local expected=$2; shift 2
  refusals=$((refusals + 1))
  printf '%s' "$expected" >"$work/refused-$refusals.expected"
  printf '%s\0' "$@" >"$work/refused-$refusals.args"
}
run_refusal() {
  local i=$1 code=0 args
  mapfile -d '' args <"$work/refused-$i.args"
  timeout 60 "$DFBWALL" "${args[@]}" >"$work/refused-$i.out" 2>"$work/refused-$i.err" || code=$?
  echo "$code" >"$work/refused-$i.code"
}
check_refusals() {
  local i args expected code
  for ((i = 1; i <= refusals; ++i)); do
    while [ "$(jobs -rp | wc -l)" -ge 4 ]; do wait -n || true; done
    run_refusal "$i" &
  done
  wait
  for ((i = 1; i <= refusals; ++i)); do
    mapfile -d '' args <"$work/refused-$i.args"
    expected=$(cat "$work/refused-$i.expected")
    code=$(cat "$work/refused-$i.code")
    [ "$code" -eq 2 ] || fail "dfbwall ${args[*]}: exit $code, expected 2"
    grep -qF -- "$expected" "$work/refused-$i.err" ||
      fail "dfbwall ${args[*]}: no '$expected' in: $(cat "$work/refused-$i.err")"
    [ ! -s "$work/refused-$i.out" ] || fail "dfbwall ${args[*]} started something: $(cat "$work/refused-$i.out")"
  done
  [ ! -e "$work/refused.png" ] || fail "a refused command line wrote an image"
}
for option in $(options "$serve_command
$relay_command
$show_command" | sort -u); do
  takes "$render_job" "$option" ||
    refused render "dfbwall: error: $option is not an option of the render job; dfbwall " \
      --size 16x16 --image "$work/refused.png" "$option" 1
done
for option in $(options "$render_job
$relay_command
$show_command" | sort -u); do
  takes "$serve_command" "$option" ||
    refused serve "dfbwall serve: error: $option is not an option of serve; " \
      serve --wall "$layout" --process 0 --listen 127.0.0.1:0 --offscreen "$option"
done
for option in $(options "$render_job
$serve_command
$show_command" | sort -u); do
  takes "$relay_command" "$option" ||
    refused relay "dfbwall relay: error: $option is not an option of relay; " \
      relay --listen 127.0.0.1:0 --wall 127.0.0.1:1 "$option"
done
for option in $(options "$render_job
$serve_command
$relay_command" | sort -u); do
  takes "$show_command" "$option" ||
    refused show "dfbwall show: error: $option is not an option of show; " \
      show --connect 127.0.0.1:1 "$work/refused.png" "$option"
done
# show: a wall to connect to, and one way to end.
refused show "dfbwall show: error: show needs --connect HOST:PORT" show "$work/refused.png"
refused show "dfbwall show: error: --loop and --once" \
  show --connect 127.0.0.1:1 --loop --once "$work/refused.png"
refused show "dfbwall show: error: $work/none-%03d.png: no file in" \
  show --connect 127.0.0.1:1 "$work/none-%03d.png"
# Before the subcommand's name, even an option it takes goes to the render job: refused too.
refused serve "dfbwall serve: error: --offscreen was given before serve" \
  --offscreen serve --wall "$layout" --process 0 --listen 127.0.0.1:0
refused serve "dfbwall serve: error: --scene is not an option of serve; the render job" \
  --scene builtin:spheres serve --wall "$layout" --process 0 --listen 127.0.0.1:0
check_refusals
echo "refused: $refusals options given to a command that does not take them"

# dfbwall-layout takes one layout and no option but --help.
"$DFBWALL_LAYOUT" --help >"$work/layout-help.out" || fail "dfbwall-layout --help exited non-zero"
grep -q "^usage: dfbwall-layout LAYOUT.toml" "$work/layout-help.out" || fail "dfbwall-layout --help"
code=0
"$DFBWALL_LAYOUT" --wall "$layout" 2>"$work/layout-refused.err" || code=$?
[ "$code" -eq 2 ] && grep -q "^dfbwall-layout: error: --wall is not an option of dfbwall-layout" \
  "$work/layout-refused.err" || fail "dfbwall-layout --wall: exit $code"
# (Its whole output first: grep -q stops reading at the match, and under pipefail the writer's
# SIGPIPE would fail the test now and then.)
layoutText=$("$DFBWALL_LAYOUT" "$layout") || fail "dfbwall-layout LAYOUT exited non-zero"
grep -qx "processes 1" <<<"$layoutText" || fail "dfbwall-layout LAYOUT"

# 3. Good command lines still run.
mpi -np 2 "$DFBWALL" --wall "$layout" --dry-run --tile-size 32 --mode gather >"$work/dry.out" 2>&1 ||
  fail "--dry-run failed"
grep -q "^layout .*1x1.toml" "$work/dry.out" || fail "--dry-run printed no plan"
mpi -np 1 "$DFBWALL" --scene builtin:spheres --renderer primary --size 32x24 --spp 1 --frames 2 \
  --seed 3 --threads 1 --distribution static --timeout 30 --memory-limit 1G --quiet \
  --image "$work/job.png" >"$work/image.out" 2>&1 || fail "an image run failed"
[ -s "$work/job.png" ] || fail "the image run wrote no image"

"$DFBWALL" serve --wall "$layout" --process 0 --listen 127.0.0.1:0 --offscreen --timeout 10 \
  --frames-in-flight 2 --handler-threads 1 --stats "$work/serve.jsonl" --capture-root "$work" \
  --capture-quota 64M >"$work/serve.out" 2>"$work/serve.err" &
serve=$!
waitFor 30 grep -q "wall service on" "$work/serve.out" || fail "serve did not start"
wallAddress=$(sed -n 's/^dfbwall: wall service on \([^ ]*\).*/\1/p' "$work/serve.out")
"$DFBWALL" relay --listen 127.0.0.1:0 --wall "$wallAddress" --timeout 10 \
  --stats "$work/relay.jsonl" >"$work/relay.out" 2>"$work/relay.err" &
relay=$!
waitFor 30 grep -q "relay on" "$work/relay.out" || fail "the relay did not start"
relayAddress=$(sed -n 's/^dfbwall: relay on \([^ ]*\) .*/\1/p' "$work/relay.out")
mpi -np 1 "$DFBWALL" --connect "$relayAddress" --codec raw --renderer pattern --frames 2 --quiet \
  --timeout 30 --capture "$work/captures" >"$work/job.out" 2>&1 || fail "a job through the relay failed"
ls "$work"/captures/*/frame-*.png >/dev/null 2>&1 || fail "the wall captured nothing of the job"
"$DFBWALL" show --connect "$relayAddress" --codec raw --window full --fps 50 --once \
  --filter nearest --background "#102030" --timeout 30 --memory-limit 1G --capture-every 1 \
  --capture "$work/pictures" --stats "$work/show.jsonl" --quiet "$work/job.png" "$work/job.png" \
  >"$work/show.out" 2>&1 || fail "show through the relay failed"
ls "$work"/pictures/*/frame-000002.png >/dev/null 2>&1 || fail "the wall captured no picture"
[ "$(grep -c '^{"frame"' "$work/show.jsonl")" -eq 2 ] || fail "show --stats: not 2 frames"
for p in relay serve; do
  kill -USR1 "${!p}"
  waitFor 20 sh -c "! kill -0 ${!p} 2>/dev/null" || fail "$p did not stop on SIGUSR1"
  wait "${!p}" || fail "$p exited non-zero after SIGUSR1"
  eval "$p=''"
done
[ -s "$work/serve.jsonl" ] || fail "serve --stats is empty"
echo "ran: --dry-run, an image, a job and a picture through dfbwall relay to dfbwall serve"
