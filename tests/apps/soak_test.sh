#!/usr/bin/env bash
# Soak (label 'stress'): a pattern wall of small displays for FRAMES frames (default 100 000);
# every rank's resident memory may grow by less than 2 MiB between warm-up (10% of the frames)
# and the end. Statistics are streamed (--stats), so their size does not count against memory.
#   soak_test.sh LAYOUT [FRAMES]
# Needs DFBWALL and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
layout=$1 frames=${2:-100000}
work=$(mktemp -d)
job=""
trap '[ -n "$job" ] && kill -9 "$job" 2>/dev/null; rm -rf "$work"' EXIT
"$MPIEXEC" -n 5 --oversubscribe --bind-to none "$DFBWALL" --wall "$layout" --offscreen \
  --renderer pattern --frames "$frames" --quiet --timeout 30 --stats "$work/stats.jsonl" \
  >"$work/log" 2>&1 &
job=$!
frames_done() { local n; n=$(grep -c '^{"frame":' "$work/stats.jsonl" 2>/dev/null || true); echo "${n:-0}"; }
rss() {  # "pid:KiB ..." of every rank
  for p in $(pgrep -P "$job" -x dfbwall | sort -n); do
    echo -n "$p:$(awk '/^VmRSS:/ {print $2}' "/proc/$p/status" 2>/dev/null || echo 0) "
  done
}
wait_frames() {
  while [ "$(frames_done)" -lt "$1" ]; do
    kill -0 "$job" 2>/dev/null || { echo "FAIL: the job ended early"; cat "$work/log"; exit 1; }
    sleep 0.5
  done
}
start=$(date +%s)
wait_frames $((frames / 10))
warm=$(rss)
wait_frames $((frames * 95 / 100))
late=$(rss)
set +e; wait "$job"; code=$?; set -e; job=""
[ "$code" -eq 0 ] || { echo "FAIL: exit $code"; cat "$work/log"; exit 1; }
echo "$frames frames in $(( $(date +%s) - start )) s; RSS KiB at 10% and 95%:"
status=0
for w in $warm; do
  pid=${w%%:*} before=${w#*:}
  after=$(tr ' ' '\n' <<<"$late" | grep "^$pid:" | cut -d: -f2)
  growth=$((after - before))
  echo "  rank pid $pid: $before -> $after KiB (growth $growth KiB)"
  [ "$growth" -lt 2048 ] || { echo "FAIL: grew by 2 MiB or more"; status=1; }
done
tail -n 1 "$work/stats.jsonl" | grep -q '^{"summary":{"frames":'"$frames" || { echo "FAIL: summary"; status=1; }
exit $status
