# shellcheck shell=bash disable=SC2154
# Sourced by the tests that watch a running wall through its captures (wall_survives_test.sh,
# relay_rejoin_test.sh, cluster_test.sh). The sourcing script sets `work` (its temporary folder,
# captures in $work/cap/DISPLAY/) and, for pidOf, `serve` (the pid of the wall's mpirun).

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN {printf "%.2f", b - a}'; }

# The newest frame a display has presented (its newest capture); captures older than the newest
# 40 are deleted on the way, so a long run does not fill the disk.
latest() {
  local dir="$work/cap/$1" newest
  newest=$(ls "$dir" 2>/dev/null | tail -1)
  [ -n "$newest" ] || { echo 0; return; }
  ls "$dir" | head -n -40 | sed "s|^|$dir/|" | xargs -r rm -f
  ls "$work"/cap/wall-*.png 2>/dev/null | head -n -40 | xargs -r rm -f
  echo $((10#$(echo "$newest" | tr -dc 0-9)))
}

# advanced FRAME DISPLAY...: every display presented a frame after FRAME.
advanced() {
  local frame=$1 d; shift
  for d in "$@"; do [ "$(latest "$d")" -gt "$frame" ] || return 1; done
}

# presentedSince T0 FRAME DISPLAY...: the seconds from T0 (a `now`) until the last of the displays
# wrote its first capture after FRAME, read from the captures' times: when the wall presented
# again, not when a poll of the captures saw it (a poll's own delay, its processes started every
# 0.1 s, grows with the machine's load). Fails when a display has no capture after FRAME.
presentedSince() {
  local t0=$1 frame=$2 d first t last=0; shift 2
  for d in "$@"; do
    first=$(ls "$work/cap/$d" 2>/dev/null |
      awk -v n="$frame" '{x = $0; gsub(/[^0-9]/, "", x); if (x + 0 > n) {print; exit}}')
    [ -n "$first" ] || return 1
    t=$(stat -c %.3Y "$work/cap/$d/$first")
    last=$(awk -v a="$last" -v b="$t" 'BEGIN {print (b > a) ? b : a}')
  done
  awk -v a="$t0" -v b="$last" 'BEGIN {printf "%.2f", b - a}'
}

# waitFor SECONDS CONDITION...: polls CONDITION every 0.1 s; false when it never held.
waitFor() {
  local until
  until=$(awk -v a="$(now)" -v s="$1" 'BEGIN {printf "%.3f", a + s}'); shift  # not %.6g
  while awk -v t="$(now)" -v u="$until" 'BEGIN {exit !(t < u)}'; do
    "$@" && return 0
    sleep 0.1
  done
  return 1
}

# Wall process N's pid among the children of the wall's mpirun ($serve) only: another test may
# run a wall of the same layout meanwhile.
pidOf() {
  for p in $(pgrep -P "$serve"); do
    [ "$(cat /proc/"$p"/comm 2>/dev/null)" = dfbwall ] || continue
    if tr '\0' '\n' <"/proc/$p/environ" | grep -qx "OMPI_COMM_WORLD_RANK=$1"; then echo "$p"; fi
  done
}

freePort() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

# within SECONDS BOUND: true when SECONDS < BOUND. The bounds are the issue's, checked by the plain
# build; a sanitizer build (CI's second pass: its processes start and draw 2-4x slower) stretches
# them by DFBWALL_TIME_SCALE, which CMake sets for it.
within() { awk -v t="$1" -v b="$2" -v s="${DFBWALL_TIME_SCALE:-1}" 'BEGIN {exit !(t < b * s)}'; }
