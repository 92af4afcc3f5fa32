#!/usr/bin/env bash
# dfbwall across emulated hosts (scripts/cluster): one network namespace per host, TCP between
# them over a bridge, every link capped at 1 Gbit/s both ways. One scenario per call:
#   cluster_test.sh equals-single LAYOUT RENDER_HOSTS [dfbwall options for both runs...]
#   cluster_test.sh compression   LAYOUT RENDER_HOSTS
#   cluster_test.sh rank-killed   LAYOUT RENDER_HOSTS RANK
#   cluster_test.sh link-cut      LAYOUT RENDER_HOSTS HOST TIMEOUT
#   cluster_test.sh link-flap     LAYOUT RENDER_HOSTS HOST TIMEOUT
#   cluster_test.sh service       LAYOUT RENDER_HOSTS
#   cluster_test.sh two-jobs      LAYOUT RENDER_HOSTS   (2: one job from each render host)
#   cluster_test.sh relay         LAYOUT RENDER_HOSTS
#   cluster_test.sh survive       LAYOUT RENDER_HOSTS   (wall processes 0, 1 on wall1; 2, 3 on wall2)
# Needs DFBWALL, COMPARE (compare_captures), MPIEXEC and CLUSTER (scripts/cluster) in the
# environment, root and CAP_NET_ADMIN; without them it exits 77 (CTest: skipped), saying why.
# Every call claims a cluster id of its own (--id auto), so tests can run in parallel, and
# removes its hosts on every way out.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
id="" job="" serve="" relay="" restarted=""
cleanup() {
  [ -z "$relay" ] || kill -9 "$relay" 2>/dev/null || true
  [ -z "$restarted" ] || kill -9 "$restarted" 2>/dev/null || true
  [ -z "$job" ] || kill -9 "$job" 2>/dev/null || true
  [ -z "$serve" ] || kill -9 "$serve" 2>/dev/null || true
  [ -z "$id" ] || "$CLUSTER" down --id "$id" >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 143' TERM
trap 'exit 130' INT

skip() { echo "SKIPPED: $*"; exit 77; }
fail() {
  echo "FAIL: $*"
  [ ! -f "$work/log" ] || { echo "--- job output:"; cat "$work/log"; }
  [ ! -f "$work/b.out" ] || { echo "--- job b output:"; cat "$work/b.out"; }
  [ ! -f "$work/serve.err" ] || { echo "--- serve output:"; cat "$work/serve.out" "$work/serve.err"; }
  [ ! -f "$work/relay.err" ] || { echo "--- relay output:"; cat "$work/relay.out" "$work/relay.err"; }
  exit 1
}
[ "$(id -u)" -eq 0 ] || skip "emulated hosts need root (network namespaces, veth pairs, tc); CI runs as root"
command -v ip >/dev/null && command -v tc >/dev/null || skip "iproute2 is missing (scripts/setup installs it)"
probe="dfbwprobe$$"
if ! ip netns add "$probe" 2>"$work/probe"; then
  skip "cannot create a network namespace, CAP_NET_ADMIN missing? ($(cat "$work/probe"))"
fi
ip netns del "$probe"

build=$(cd "$(dirname "$DFBWALL")/.." && pwd)
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }
# now, latest, advanced, presentedSince, waitFor, freePort (since: its own, to a tenth of a
# second)
source "$(dirname "${BASH_SOURCE[0]}")/wall_watch.sh"
since() { awk -v a="$1" -v b="$(now)" 'BEGIN {printf "%.1f", b - a}'; }
# Per-frame values of FIELD in a stats file, one per line.
# (JSON Lines as dfbwall streams them: no space after the colon; older files had one.)
field() { grep -o "\"$2\": *[0-9.]*" "$1" | sed 's/.*: *//'; }

# up LAYOUT RENDER_HOSTS [scripts/cluster options]: the hosts of the layout plus the render
# hosts, 1 Gbit/s links.
up() {
  "$CLUSTER" up --id auto --holder $$ --build "$build" --wall "$1" --render-hosts "$2" --rate 1gbit "${@:3}" \
    >"$work/up" 2>&1 || { cat "$work/up"; fail "scripts/cluster up"; }
  id=$(sed -n 's/^cluster \([0-9]*\):.*/\1/p' "$work/up")
  mpirun=$(sed -n 's/^run: \([^ ]*\) .*/\1/p' "$work/up")
  [ -n "$id" ] && [ -x "$mpirun" ] || { cat "$work/up"; fail "no cluster id or mpirun in the output of up"; }
  cat "$work/up"
}
# The host of world rank RANK, and that rank's process id (in its host's namespace).
host_of() { sed -n "$(($1 + 1))p" "$(dirname "$mpirun")/rank-hosts"; }
pid_of_rank() {
  local p
  for p in $(ip netns pids "dfbw$id-$(host_of "$1")" 2>/dev/null); do
    [ "$(cat "/proc/$p/comm" 2>/dev/null)" = dfbwall ] &&
      tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$1" && echo "$p"
  done
  return 0
}
# Starts the job in the background (output in $work/log) and waits until every rank runs and
# frames flow (rank 0's first progress line, a second in: every TCP connection is up by then).
start() {
  "$mpirun" "$DFBWALL" "$@" >"$work/log" 2>&1 &
  job=$!
  local ranks r
  ranks=$(wc -l <"$(dirname "$mpirun")/rank-hosts")
  for _ in $(seq 1 100); do
    for ((r = 0; r < ranks; ++r)); do [ -n "$(pid_of_rank "$r")" ] || break; done
    [ "$r" -eq "$ranks" ] && break
    kill -0 "$job" 2>/dev/null || fail "the job ended while starting"
    sleep 0.1
  done
  [ "$r" -eq "$ranks" ] || fail "not every rank was running 10 s after the start"
  for _ in $(seq 1 300); do
    grep -q '^frame [0-9]' "$work/log" && return
    kill -0 "$job" 2>/dev/null || fail "the job ended before its first progress line"
    sleep 0.1
  done
  fail "no frame 30 s after the start"
}
# Waits at most SECONDS for the job; sets `code` (124: still running, then killed).
finish() {
  local deadline
  deadline=$(awk -v s="$1" -v t="$(now)" 'BEGIN {printf "%.3f", t + s}')
  while kill -0 "$job" 2>/dev/null && awk -v d="$deadline" -v t="$(now)" 'BEGIN {exit !(t < d)}'; do
    sleep 0.1
  done
  if kill -0 "$job" 2>/dev/null; then
    kill -9 "$job" 2>/dev/null || true
    code=124
  else
    set +e
    wait "$job"
    code=$?
    set -e
  fi
  job=""
}

scenario=$1; shift
case "$scenario" in
  equals-single)
    # Invariant 2 across hosts: the captures equal a one-process render byte for byte.
    layout=$1 hosts=$2; shift 2
    common=(--frames 3 --spp 2 --seed 11 "$@")
    up "$layout" "$hosts"
    "$mpirun" "$DFBWALL" --wall "$layout" --offscreen --capture "$work/cap" --stats "$work/stats.json" \
      --quiet "${common[@]}" >"$work/log" 2>&1 || fail "the wall run failed"
    # The layout's hosts are the hosts' real names here: no host warning.
    ! grep -q "warning" "$work/log" || fail "host warnings although every rank ran on its layout host"
    # Every piece crossed hosts: this ran over TCP between namespaces, not shared memory.
    [ "$(field "$work/stats.json" wall_pieces | sort -u)" = "$(field "$work/stats.json" wall_pieces_to_other_hosts | sort -u)" ] \
      || fail "not every piece went to another host"
    "$MPIEXEC" -n 1 "$DFBWALL" --size "$(canvas "$layout")" --image "$work/full.png" --quiet "${common[@]}"
    "$COMPARE" "$layout" "$work/cap" "$work/full.png" 3
    ;;
  compression)
    # Snappy engages on exactly the messages that leave a host: with every piece above the
    # compression threshold, messages compressed = pieces to other hosts, every frame.
    layout=$1 hosts=$2
    up "$layout" "$hosts"
    for variant in default within-host off; do
      options=()
      [ "$variant" = within-host ] && options=(--compress-within-host)
      [ "$variant" = off ] && options=(--no-compress)
      "$mpirun" "$DFBWALL" --wall "$layout" --offscreen --renderer pattern --tile-size 32 --frames 4 \
        --stats "$work/$variant.json" --quiet ${options[@]+"${options[@]}"} >"$work/log" 2>&1 \
        || fail "the $variant run failed"
      paste <(field "$work/$variant.json" frame) <(field "$work/$variant.json" wall_pieces) \
        <(field "$work/$variant.json" wall_pieces_to_other_hosts) \
        <(field "$work/$variant.json" messages_compressed) \
        <(field "$work/$variant.json" wall_bytes_sent) <(field "$work/$variant.json" wall_bytes_raw) \
        >"$work/$variant.tsv"
      [ "$(wc -l <"$work/$variant.tsv")" -eq 4 ] || fail "$variant: expected 4 frames in the stats"
      while read -r frame pieces other compressed wire raw; do
        echo "$variant frame $frame: $pieces pieces, $other to other hosts, $compressed compressed, $wire bytes on the wire, $raw raw"
        [ "$other" -gt 0 ] && [ "$other" -lt "$pieces" ] || fail "frame $frame: the layout should send pieces both within and across hosts"
        case "$variant" in
          default)
            [ "$compressed" -eq "$other" ] || fail "frame $frame: $compressed messages compressed, $other pieces crossed hosts"
            [ "$wire" -lt "$raw" ] || fail "frame $frame: $wire bytes on the wire, not fewer than the raw $raw" ;;
          within-host)
            [ "$compressed" -eq "$pieces" ] || fail "frame $frame: --compress-within-host compressed $compressed of $pieces pieces" ;;
          off)
            [ "$compressed" -eq 0 ] || fail "frame $frame: --no-compress compressed $compressed messages"
            # Uncompressed, the wire carries each piece plus the messenger's 16-byte envelope.
            [ "$wire" -eq $((raw + 16 * pieces)) ] || fail "frame $frame: $wire wire bytes, expected $raw + 16 x $pieces" ;;
        esac
      done <"$work/$variant.tsv"
    done
    ;;
  rank-killed)
    # kill -9 of a rank on another host ends the job, naming the rank and its host, within 10 s.
    layout=$1 hosts=$2 rank=$3
    up "$layout" "$hosts"
    start --wall "$layout" --offscreen --renderer pattern --frames 1000000 --timeout 30
    host=$(host_of "$rank") victim=$(pid_of_rank "$rank")
    t0=$(now)
    kill -9 "$victim"
    finish 20
    elapsed=$(since "$t0")
    cat "$work/log"
    [ "$code" -ne 124 ] || fail "the job still ran 20 s after rank $rank was killed"
    [ "$code" -ne 0 ] || fail "exit code 0 after rank $rank was killed"
    awk -v e="$elapsed" 'BEGIN {exit !(e <= 10)}' || fail "the job took $elapsed s to end, more than 10"
    grep -qE "rank $rank .*$host" "$work/log" || fail "no message naming rank $rank and host $host"
    echo "killed rank $rank on $host: the job ended after $elapsed s with exit $code, naming both"
    ;;
  link-cut)
    # A link cut longer than --timeout: a named error and the end of the job within
    # --timeout + 3 s. The link returns once the error is out (at least --timeout after
    # the cut): OpenMPI's mpirun cannot end a job while a host's daemon is unreachable (it
    # waits for that daemon's ranks, which have ended with their own errors by then).
    layout=$1 hosts=$2 host=$3 timeout=$4
    up "$layout" "$hosts"
    start --wall "$layout" --offscreen --renderer pattern --frames 1000000 --timeout "$timeout"
    t0=$(now)
    "$CLUSTER" link "$host" down --id "$id"
    while kill -0 "$job" 2>/dev/null && { ! grep -q "dfbwall: error" "$work/log" ||
      awk -v t="$(since "$t0")" -v l="$timeout" 'BEGIN {exit !(t < l)}'; } &&
      awk -v t="$(since "$t0")" -v l="$((timeout + 3))" 'BEGIN {exit !(t < l)}'; do
      sleep 0.1
    done
    down=$(since "$t0")
    errorAt=$down  # the loop left when the first error was out (or at the limit)
    "$CLUSTER" link "$host" up --id "$id"
    finish $((timeout + 10))
    elapsed=$(since "$t0")
    cat "$work/log"
    [ "$code" -ne 124 ] || fail "the job still ran $((timeout + 10)) s after the cut"
    [ "$code" -ne 0 ] || fail "exit code 0 after a cut longer than --timeout"
    grep -qE "dfbwall: error on rank [0-9]+( \([^)]*\))?: .*(within|after) ${timeout}000 ms" "$work/log" \
      || fail "no dfbwall error naming what did not arrive within --timeout"
    # The cause names who is cut off: ranks behind the link from one side, or the other side's
    # ranks from a rank on the cut host.
    first=$(grep -m1 'dfbwall: error on rank' "$work/log")
    if grep -q "^dfbwall: error on rank [0-9]* ($host)" <<<"$first"; then
      grep -q "not answering: rank" <<<"$first" || fail "the error names no rank as not answering"
    else
      grep -q "not answering: .*($host)" <<<"$first" || fail "the error does not name a rank on $host as not answering"
    fi
    awk -v e="$errorAt" -v l="$((timeout + 3))" 'BEGIN {exit !(e <= l)}' \
      || fail "the first error came $errorAt s after the cut, more than --timeout + 3 = $((timeout + 3)) s"
    # mpirun's own exit waits for TCP to retransmit its abort to the host once the link is back
    # (about 1-2 s on an idle machine, more under load): bounded, but not by our deadlines.
    awk -v e="$elapsed" -v l="$((timeout + 6))" 'BEGIN {exit !(e <= l)}' \
      || fail "the job ended $elapsed s after the cut, more than --timeout + 6 = $((timeout + 6)) s"
    echo "cut $host (--timeout $timeout): first error after $errorAt s, job ended after $elapsed s, exit $code"
    ;;
  link-flap)
    # A 1 s link flap, shorter than --timeout: the run goes on and its captures are right.
    layout=$1 hosts=$2 host=$3 timeout=$4
    frames=600  # about 3 s at full speed: the run outlasts the flap
    up "$layout" "$hosts"
    start --wall "$layout" --offscreen --renderer pattern --frames "$frames" --timeout "$timeout" \
      --capture "$work/cap" --stats "$work/stats.json"
    kill -0 "$job" 2>/dev/null || fail "the run ended before the flap; give it more frames"
    "$CLUSTER" link "$host" down --id "$id"
    sleep 1
    "$CLUSTER" link "$host" up --id "$id"
    finish 90
    [ "$code" -eq 0 ] || fail "exit $code after a 1 s flap (--timeout $timeout)"
    # The flap held a frame up: proof it hit the run, not the time before or after it.
    stall=$(field "$work/stats.json" frame_ms | sort -g | tail -1)
    awk -v s="$stall" 'BEGIN {exit !(s >= 500)}' || fail "no frame took 500 ms or more (longest $stall ms): the flap missed the run"
    "$MPIEXEC" -n 1 "$DFBWALL" --renderer pattern --frames "$frames" --size "$(canvas "$layout")" \
      --image "$work/full.png" --quiet
    "$COMPARE" "$layout" "$work/cap" "$work/full.png" "$frames"
    echo "1 s flap of $host: the run finished (longest frame $stall ms) and its captures are right"
    ;;
  service)
    # The wall as a service across hosts (README, "A wall that stays up"): `dfbwall serve` on
    # the wall hosts alone, started once, takes render jobs from the render hosts one after
    # another, each its own mpirun: the path tracer (raw), scivis with 4 bricks (snappy), the
    # pattern (snappy). Their captures, written by the wall processes, equal the one-process
    # render; render rank 0 receives no pixels. A second job while one is connected is refused
    # at once (busy); kill -9 of a render rank leaves the wall up and the next job (--wait) works.
    layout=$1 hosts=$2
    up "$layout" "$hosts"
    state=$(dirname "$mpirun")
    renderHosts=()
    for ((h = 1; h <= hosts; ++h)); do renderHosts+=("render$h"); done
    mapfile -t wallHosts < <(tail -n +$((hosts + 1)) "$state/rank-hosts" | awk '!seen[$0]++')
    for h in "${wallHosts[@]}"; do
      [[ " ${renderHosts[*]} " != *" $h "* ]] || fail "$layout puts a wall process on render host $h"
    done
    address=$(awk -v h="${wallHosts[0]}" '$1 == h {print $3}' "$state/hosts")
    port=7000  # a host of its own: nothing else listens there
    # The token in a file serve creates (mode 0600), never on a command line or in a log.
    tokenFile=$work/wall-token
    "$CLUSTER" mpirun-hosts "${wallHosts[@]}" --id "$id" -- "$DFBWALL" serve --wall "$layout" \
      --listen "0.0.0.0:$port" --offscreen --max-jobs 1 --timeout $((5 * ${DFBWALL_TIME_SCALE:-1})) --token-file "$tokenFile" --stats "$work/serve.jsonl" \
      --capture-root "$work" >"$work/serve.out" 2>"$work/serve.err" &
    serve=$!
    for _ in $(seq 200); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
    grep -qx "dfbwall: wall service on $address:$port  token: --token-file $tokenFile" "$work/serve.out" \
      || fail "serve did not start on ${wallHosts[0]} ($address:$port) with the token file given"
    [ "$(stat -c %a "$tokenFile")" = 600 ] || fail "serve created $tokenFile with mode $(stat -c %a "$tokenFile")"
    token=$(cat "$tokenFile")
    if grep -qF "$token" "$work/serve.out" "$work/serve.err"; then fail "the token is in serve's log"; fi
    # The wall's processes, one per layout process, each on its host: they must outlive every job.
    wallPids() {
      local h p
      for h in "${wallHosts[@]}"; do
        for p in $(ip netns pids "dfbw$id-$h" 2>/dev/null); do
          [ "$(cat "/proc/$p/comm" 2>/dev/null)" = dfbwall ] && echo "$p"
        done
      done | sort -n | tr '\n' ' '
      return 0
    }
    wall=$(wallPids)
    [ "$(wc -w <<<"$wall")" -eq "$("$COMPARE" --info "$layout" | cut -d' ' -f1)" ] \
      || fail "expected one serve process per layout process on the wall hosts, found: $wall"
    connect=(--connect "$address:$port" --token-file "$tokenFile")

    # job NAME FRAMES CODEC [scene options]: a render job on the render hosts, then its
    # one-process reference, compared display by display.
    job() {
      local name=$1 frames=$2 codec=$3 t0 b
      shift 3
      t0=$(now)
      "$CLUSTER" mpirun-hosts "${renderHosts[@]}" --id "$id" -- "$DFBWALL" "${connect[@]}" ${wait:-} \
        --codec "$codec" --frames "$frames" --quiet --timeout 30 --capture "$work/$name" \
        --stats "$work/$name.jsonl" "$@" >"$work/log" 2>&1 || fail "job $name ($codec) failed"
      echo "job $name ($codec): $(since "$t0") s"
      [ "$(field "$work/$name.jsonl" rank0_pixel_bytes_received | wc -l)" -eq "$frames" ] \
        || fail "job $name: no rank0_pixel_bytes_received for each of its $frames frames"
      for b in $(field "$work/$name.jsonl" rank0_pixel_bytes_received); do
        [ "$b" = 0 ] || fail "job $name: render rank 0 received $b pixel bytes"
      done
      "$MPIEXEC" -n 1 "$DFBWALL" --size "$(canvas "$layout")" --frames "$frames" --quiet \
        --image "$work/$name-full.png" "$@" || fail "the one-process reference of $name failed"
      "$COMPARE" "$layout" "$work/$name" "$work/$name-full.png" "$frames" || fail "job $name ($codec)"
    }
    job cornell 2 raw --scene builtin:cornell --spp 2 --seed 11
    job bricks 2 snappy --renderer scivis --scene builtin:wavelet --bricks 4 --tile-size 32
    job pattern 3 snappy --renderer pattern
    [ "$(grep -c "job from ${renderHosts[0]}: $hosts render ranks" "$work/serve.err")" -eq 3 ] \
      || fail "the wall did not log 3 jobs from ${renderHosts[0]} with $hosts render ranks"

    # A job that runs until stopped; a second one meanwhile is refused at once.
    "$CLUSTER" mpirun-hosts "${renderHosts[@]}" --id "$id" -- "$DFBWALL" "${connect[@]}" \
      --renderer pattern --frames 0 --timeout 30 >"$work/log" 2>&1 &
    job=$!
    for _ in $(seq 300); do
      grep -q '^frame [0-9]' "$work/log" && break
      kill -0 "$job" 2>/dev/null || fail "the long job ended before its first progress line"
      sleep 0.1
    done
    grep -q '^frame [0-9]' "$work/log" || fail "the long job showed no frame within 30 s"
    t0=$(now)
    if "$CLUSTER" mpirun-hosts "${renderHosts[-1]}" --id "$id" -- "$DFBWALL" "${connect[@]}" \
      --renderer pattern --frames 1 --quiet --timeout 30 >"$work/busy.out" 2>&1; then
      cat "$work/busy.out"
      fail "a second job was accepted while one was connected"
    fi
    busy=$(since "$t0")
    grep -q "busy: a job from ${renderHosts[0]} is connected" "$work/busy.out" \
      || { cat "$work/busy.out"; fail "no busy error for the second job"; }
    # At once: well before the job's --timeout (30 s), mpirun's start on the host included.
    awk -v t="$busy" 'BEGIN {exit !(t < 10)}' || fail "the busy refusal took $busy s (mpirun included)"

    # kill -9 of a render rank (the last, on the last render host) in the middle of the job.
    victim=""
    for p in $(ip netns pids "dfbw$id-${renderHosts[-1]}" 2>/dev/null); do
      [ "$(cat "/proc/$p/comm" 2>/dev/null)" = dfbwall ] && victim=$p
    done
    [ -n "$victim" ] || fail "no render rank on ${renderHosts[-1]}"
    kill -9 "$victim"
    finish 20
    [ "$code" -ne 124 ] || fail "the long job still ran 20 s after one of its ranks was killed"
    kill -0 "$serve" 2>/dev/null || fail "the wall died with the killed job"
    # mpirun ends rank 0 too: its connection closes and the wall drops the job at once (--wait
    # covers the moment until it has).
    t0=$(now)
    wait=--wait job after 2 snappy --renderer pattern
    after=$(since "$t0")
    grep -q "dropping the job from ${renderHosts[0]}" "$work/serve.err" \
      || fail "the wall did not say it dropped the killed job"
    [ "$(wallPids)" = "$wall" ] || fail "the wall's processes changed: $wall then $(wallPids)"
    [ "$(wc -l <"$work/serve.jsonl")" -eq 5 ] || fail "serve --stats: $(wc -l <"$work/serve.jsonl") job lines, expected 5"

    kill -USR1 "$serve"
    for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$serve" 2>/dev/null && fail "serve did not stop within 10 s of SIGUSR1"
    set +e
    wait "$serve"
    code=$?
    set -e
    serve=""
    [ "$code" -eq 0 ] || fail "serve exited $code after SIGUSR1"
    echo "PASS: 5 jobs from ${renderHosts[*]} on one wall on ${wallHosts[*]} (raw, snappy, snappy, killed, after);" \
      "busy refused in $busy s, the job after the kill done $after s after it"
    ;;
  two-jobs)
    # Two jobs at once on a wall across hosts (docs/service.md, "Several jobs at once"): `serve
    # --max-jobs 2` on the wall hosts; a path-traced job from render1 and a scivis job with 2
    # bricks from render2, in overlapping windows that cross display and wall-host borders, each
    # routed straight to the processes its window touches. Each job's captures equal its
    # one-process render at its window's size; neither job's rank 0 receives a pixel; the first
    # keeps presenting after the second ended.
    layout=$1 hosts=$2
    [ "$hosts" -eq 2 ] || fail "two-jobs runs one job from each of 2 render hosts"
    up "$layout" "$hosts"
    state=$(dirname "$mpirun")
    mapfile -t wallHosts < <(tail -n +$((hosts + 1)) "$state/rank-hosts" | awk '!seen[$0]++')
    address=$(awk -v h="${wallHosts[0]}" '$1 == h {print $3}' "$state/hosts")
    port=7000
    tokenFile=$work/wall-token
    "$CLUSTER" mpirun-hosts "${wallHosts[@]}" --id "$id" -- "$DFBWALL" serve --wall "$layout" \
      --listen "0.0.0.0:$port" --offscreen --timeout $((5 * ${DFBWALL_TIME_SCALE:-1})) --token-file "$tokenFile" \
      --max-jobs 2 --background "#000000" --capture-root "$work" >"$work/serve.out" 2>"$work/serve.err" &
    serve=$!
    for _ in $(seq 200); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
    grep -q "wall service on $address:$port" "$work/serve.out" || fail "serve did not start on ${wallHosts[0]}"
    connect=(--connect "$address:$port" --token-file "$tokenFile")
    # newest DIR DISPLAY: the newest captured frame's number (0: none yet).
    newest() {
      local f
      f=$(ls "$1/$2" 2>/dev/null | grep -E '^frame-[0-9]+\.png$' | sort | tail -1)
      [ -n "$f" ] || { echo 0; return; }
      f=${f#frame-}; echo $((10#${f%.png}))
    }
    scale=${DFBWALL_TIME_SCALE:-1}
    # Window a: all four displays (both wall hosts); window b: over a's top-left, two displays.
    window_a=90,70,250,170 window_b=20,20,200,150
    cornell=(--scene builtin:cornell --spp 1 --seed 11)
    bricks=(--renderer scivis --scene builtin:wavelet --bricks 2 --tile-size 32)
    "$CLUSTER" mpirun-hosts render1 --id "$id" -- "$DFBWALL" "${connect[@]}" --window "$window_a" \
      "${cornell[@]}" --frames 100000 --capture-every 5 --capture "$work/a" --stats "$work/a.jsonl" \
      --quiet --timeout 30 >"$work/log" 2>&1 &
    job=$!
    for _ in $(seq $((300 * scale))); do [ "$(newest "$work/a" r1c1)" -ge 5 ] && break; sleep 0.1; done
    [ "$(newest "$work/a" r1c1)" -ge 5 ] || fail "job a presented no 5th frame"
    t0=$(now)
    "$CLUSTER" mpirun-hosts render2 --id "$id" -- "$DFBWALL" "${connect[@]}" --window "$window_b" \
      "${bricks[@]}" --frames 3 --capture "$work/b" --stats "$work/b.jsonl" --quiet --timeout 30 \
      >"$work/b.out" 2>&1 || fail "job b failed beside job a"
    echo "job b (scivis, 2 bricks, beside a): $(since "$t0") s"
    kill -0 "$job" 2>/dev/null || fail "job a ended while b ran"
    before=$(newest "$work/a" r1c1)
    for _ in $(seq $((100 * scale))); do [ "$(newest "$work/a" r1c1)" -ge $((before + 10)) ] && break; sleep 0.1; done
    [ "$(newest "$work/a" r1c1)" -ge $((before + 10)) ] || fail "job a stopped presenting after b ended"
    kill -TERM "$job"
    finish 20
    [ "$code" -ne 124 ] || fail "job a did not stop within 20 s of SIGTERM"
    for name in a b; do
      [ "$(field "$work/$name.jsonl" rank0_pixel_bytes_received | wc -l)" -gt 0 ] || fail "job $name: no stats"
      for v in $(field "$work/$name.jsonl" rank0_pixel_bytes_received); do
        [ "$v" = 0 ] || fail "job $name: render rank 0 received $v pixel bytes"
      done
    done
    "$MPIEXEC" -n 1 "$DFBWALL" --size 250x170 --frames 5 --quiet --image "$work/a-ref.png" "${cornell[@]}" \
      || fail "the one-process reference of a"
    "$MPIEXEC" -n 1 "$DFBWALL" --size 200x150 --frames 3 --quiet --image "$work/b-ref.png" "${bricks[@]}" \
      || fail "the one-process reference of b"
    "$COMPARE" --window "$window_a" "$layout" "$work/a" "$work/a-ref.png" 5 || fail "job a's captures"
    "$COMPARE" --window "$window_b" "$layout" "$work/b" "$work/b-ref.png" 3 || fail "job b's captures"
    kill -USR1 "$serve"
    for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$serve" 2>/dev/null && fail "serve did not stop within 10 s of SIGUSR1"
    echo "PASS: a path-traced and a scivis job at once from two render hosts on a wall of two hosts;" \
      "captures equal their one-process renders; rank 0 received no pixels"
    ;;
  relay)
    # `dfbwall relay` on a gateway (README, "A wall that stays up"): the render hosts are on a
    # network of their own that reaches only gateway1 (scripts/cluster --gateway-hosts), which
    # has a leg on the wall's network too and forwards nothing. `dfbwall serve` on the wall hosts,
    # the relay on gateway1, a job on the render hosts connecting to the relay: its captures
    # equal the one-process render. The render hosts cannot open a connection to the wall.
    layout=$1 hosts=$2
    up "$layout" "$hosts" --gateway-hosts 1
    state=$(dirname "$mpirun")
    renderHosts=()
    for ((h = 1; h <= hosts; ++h)); do renderHosts+=("render$h"); done
    mapfile -t wallHosts < <(tail -n +$((hosts + 1)) "$state/rank-hosts" | awk '!seen[$0]++')
    address=$(awk -v h="${wallHosts[0]}" '$1 == h {print $3}' "$state/hosts")
    gatewayWall=$(awk '$1 == "gateway1" {print $3}' "$state/hosts")
    gatewayRender=$(awk '$1 == "gateway1" {print $5}' "$state/hosts")
    [ -n "$gatewayRender" ] || fail "gateway1 has no address on the render network"
    port=7000
    token=$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')
    "$CLUSTER" mpirun-hosts "${wallHosts[@]}" --id "$id" -- "$DFBWALL" serve --wall "$layout" \
      --listen "0.0.0.0:$port" --offscreen --timeout 5 --token "$token" --capture-root "$work" \
      >"$work/serve.out" 2>"$work/serve.err" &
    serve=$!
    "$CLUSTER" exec gateway1 --id "$id" -- "$DFBWALL" relay --listen "$gatewayRender:$port" \
      --wall "$address:$port" --token "$token" --timeout 5 --stats "$work/relay.jsonl" >"$work/relay.out" 2>"$work/relay.err" &
    relay=$!
    for _ in $(seq 200); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
    grep -q "wall service on $address:$port" "$work/serve.out" || fail "serve did not start"
    grep -qx "dfbwall: relay on $gatewayRender:$port for the wall at $address:$port" "$work/relay.out" \
      || fail "the relay did not start on gateway1"
    # The render hosts reach the relay, never the wall (nor the gateway's leg on the wall's network).
    reach() { ip netns exec "dfbw$id-$1" timeout 3 bash -c "echo >/dev/tcp/$2/$3" 2>/dev/null; }
    for h in "${renderHosts[@]}"; do
      reach "$h" "$gatewayRender" "$port" || fail "$h cannot reach the relay at $gatewayRender:$port"
      ! reach "$h" "$address" "$port" || fail "$h reaches the wall at $address:$port directly"
      ! reach "$h" "$gatewayWall" "$port" || fail "$h reaches the gateway's wall-side address"
    done
    [ "$(ip netns exec "dfbw$id-gateway1" sysctl -n net.ipv4.ip_forward)" = 0 ] || fail "gateway1 forwards"
    name=pattern frames=3
    t0=$(now)
    "$CLUSTER" mpirun-hosts "${renderHosts[@]}" --id "$id" -- "$DFBWALL" --connect "$gatewayRender:$port" \
      --token "$token" --codec snappy --frames "$frames" --quiet --timeout 30 --capture "$work/$name" \
      --renderer pattern >"$work/log" 2>&1 || fail "the job through the relay failed"
    echo "job through the relay: $(since "$t0") s"
    "$MPIEXEC" -n 1 "$DFBWALL" --size "$(canvas "$layout")" --frames "$frames" --quiet \
      --image "$work/$name-full.png" --renderer pattern || fail "the one-process reference failed"
    "$COMPARE" "$layout" "$work/$name" "$work/$name-full.png" "$frames" || fail "the job through the relay"
    grep -q "job from ${renderHosts[0]}: the wall accepted it" "$work/relay.err" || fail "the relay did not log the job"
    for _ in $(seq 100); do [ -s "$work/relay.jsonl" ] && break; sleep 0.1; done
    batches=$(grep -o '"batches_forwarded":[0-9]*' "$work/relay.jsonl" | cut -d: -f2)
    [ "${batches:-0}" -gt 0 ] || fail "the relay's --stats has no forwarded batches"
    kill -USR1 "$relay"
    wait "$relay" || fail "the relay exited non-zero after SIGUSR1"
    relay=""
    kill -USR1 "$serve"
    for _ in $(seq 100); do kill -0 "$serve" 2>/dev/null || break; sleep 0.1; done
    wait "$serve" || fail "serve exited non-zero after SIGUSR1"
    serve=""
    echo "PASS: a job on ${renderHosts[*]} (no route to the wall) rendered to the wall on ${wallHosts[*]} through" \
      "the relay on gateway1: $batches batches, captures equal the one-process render"
    ;;
  survive)
    # A wall that survives its own processes across hosts (README, "A wall that survives its
    # own nodes"): `dfbwall serve` under mpirun with recovery on the two wall hosts (the head,
    # process 0, on wall1), a render job on the render hosts with --frames 0 and a capture of
    # every frame. kill -9 of process 3 (wall2), then its documented restart inside wall2;
    # SIGSTOP/SIGCONT of process 1 (wall1); the cut of wall2's link, then its return. Each loss:
    # within the timeout + 2 s the other displays present new frames and the job goes on; each
    # return: the display presents again (the restart within 3 s of
    # joining, equal to the one-process render).
    layout=$1 hosts=$2 timeout=3
    up "$layout" "$hosts"
    renderHosts=()
    for ((h = 1; h <= hosts; ++h)); do renderHosts+=("render$h"); done
    state=$(dirname "$mpirun")
    address=$(awk '$1 == "wall1" {print $3}' "$state/hosts")
    port=7000
    token=$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')
    OMPI_MCA_orte_enable_recovery=1 "$CLUSTER" mpirun-hosts wall1 wall2 --id "$id" -- "$DFBWALL" serve \
      --wall "$layout" --listen "0.0.0.0:$port" --offscreen --timeout $timeout --token "$token" \
      --stats "$work/serve.jsonl" --capture-root "$work" >"$work/serve.out" 2>"$work/serve.err" &
    serve=$!
    for _ in $(seq 200); do grep -q "wall service on" "$work/serve.out" 2>/dev/null && break; sleep 0.1; done
    grep -q "wall service on $address:$port" "$work/serve.out" || fail "serve did not start on wall1"
    "$CLUSTER" mpirun-hosts "${renderHosts[@]}" --id "$id" -- "$DFBWALL" --connect "$address:$port" \
      --token "$token" --renderer pattern --frames 0 --quiet --timeout 30 --capture "$work/cap" \
      --capture-every 1 --stats "$work/job.jsonl" >"$work/log" 2>&1 &
    job=$!
    wallPid() {  # the serve process of wall process N on HOST
      local p
      for p in $(ip netns pids "dfbw$id-$2" 2>/dev/null); do
        [ "$(cat "/proc/$p/comm" 2>/dev/null)" = dfbwall ] &&
          tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$1" && echo "$p"
      done
      return 0
    }
    waitFor 30 advanced 5 r0c0 r0c1 r1c0 r1c1 || fail "the job's frames did not reach the wall"
    # lost N DISPLAYS...: the wall drops process N, and the displays named go on presenting.
    lost() {
      local process=$1 t0=$2 frame; shift 2
      waitFor $((timeout + 5)) grep -q "lost wall process $process" "$work/serve.err" ||
        fail "wall process $process was not dropped"
      frame=$(latest "$1")
      waitFor 5 advanced "$frame" "$@" || fail "$* did not present new frames without process $process"
      local took; took=$(presentedSince "$t0" "$frame" "$@")
      within "$took" $((timeout + 2)) ||
        fail "the other displays presented again $took s after process $process went (timeout $timeout s)"
      kill -0 "$job" 2>/dev/null || fail "the job stopped when wall process $process went"
      echo "process $process gone: $* presenting again after $took s"
    }

    victim=$(wallPid 3 wall2)
    [ -n "$victim" ] || fail "no wall process 3 on wall2"
    kill -9 "$victim"
    lost 3 "$(now)" r0c0 r0c1 r1c0
    dead=$(latest r1c1)
    ip netns exec "dfbw$id-wall2" unshare --uts sh -c "hostname wall2; exec $DFBWALL serve \
      --wall $layout --process 3 --join $address:$port --token $token --offscreen --timeout $timeout --capture-root $work" \
      >"$work/restarted.out" 2>"$work/restarted.err" &
    restarted=$!
    # From its join: a process's start-up is the host's load, not the wall's.
    waitFor 20 grep -q "joined the wall" "$work/restarted.err" || fail "the restarted process 3 did not join"
    t0=$(now)
    waitFor 10 advanced "$dead" r1c1 || { cat "$work/restarted.err"; fail "the restarted process 3 presents nothing"; }
    back=$(presentedSince "$t0" "$dead" r1c1)
    within "$back" 3 || fail "process 3 presented again only $back s after it joined"
    frame=$(latest r1c1)
    mkdir -p "$work/check/r1c1"
    cp "$work/cap/r1c1/frame-$(printf %06d "$frame").png" "$work/check/r1c1/"
    "$MPIEXEC" -n 1 "$DFBWALL" --renderer pattern --frames "$frame" --size "$(canvas "$layout")" \
      --image "$work/full.png" --quiet
    "$COMPARE" "$layout" "$work/check" "$work/full.png" "$frame" r1c1 || fail "the restarted display's frame $frame"
    echo "process 3 restarted on wall2: r1c1 presented frame $frame after $back s, equal to the one-process render"

    stopped=$(wallPid 1 wall1)
    kill -STOP "$stopped"
    lost 1 "$(now)" r0c0 r1c0 r1c1
    halted=$(latest r0c1)
    kill -CONT "$stopped"
    waitFor 10 grep -q "wall process 1 on .* is back in the wall" "$work/serve.err" ||
      fail "process 1 did not join again after SIGCONT"
    halted=$(latest r0c1)
    waitFor 10 advanced "$halted" r0c1 || fail "process 1 did not present again after SIGCONT"

    "$CLUSTER" link wall2 down --id "$id"
    t0=$(now)
    waitFor $((timeout + 5)) grep -q "lost wall process 2" "$work/serve.err" || fail "wall2's process 2 was not dropped"
    waitFor 3 sh -c "[ \$(grep -c 'lost wall process 3' '$work/serve.err') -ge 2 ]" ||
      fail "wall2's process 3 was not dropped"
    lost 2 "$t0" r0c0 r0c1
    cut=$(latest r1c0)
    "$CLUSTER" link wall2 up --id "$id"
    t0=$(now)
    waitFor 20 advanced "$cut" r1c0 r1c1 || fail "wall2's displays did not present again after its link came back"
    echo "wall2's link back: its displays presenting again after $(since "$t0") s"
    grep -q '"wall_pieces_dropped":[1-9]' "$work/job.jsonl" || fail "the job counted no dropped pieces"
    grep -q '"event":"lost","process":2' "$work/serve.jsonl" || fail "no lost event in serve --stats"

    kill -TERM "$job"
    for _ in $(seq 200); do kill -0 "$job" 2>/dev/null || break; sleep 0.1; done
    job=""
    kill -USR1 "$serve"
    # Every wall process stops, the restarted one too. (After a cut link, OpenMPI 4.1's mpirun
    # with recovery may stay up once its processes are gone: it is not waited for.)
    servePids() { for h in wall1 wall2; do for p in $(ip netns pids "dfbw$id-$h" 2>/dev/null); do
      [ "$(cat "/proc/$p/comm" 2>/dev/null)" = dfbwall ] && echo "$p"; done; done; return 0; }
    for _ in $(seq 200); do [ -z "$(servePids)" ] && break; sleep 0.1; done
    [ -z "$(servePids)" ] || fail "wall processes $(servePids | tr '\n' ' ')did not stop within 20 s of SIGUSR1"
    grep -q "stopping the wall" "$work/serve.err" || fail "the head did not say it stops the wall"
    pkill -9 -f "dfbwall-cluster/$id/hostfile-wall1-wall2" 2>/dev/null || true
    kill -9 "$serve" 2>/dev/null || true
    serve=""
    echo "PASS: kill -9, restart, SIGSTOP/SIGCONT and a cut link on two wall hosts; the job ran throughout"
    ;;
  *) echo "unknown scenario $scenario"; exit 2 ;;
esac
