# Sourced by the service tests that run a wall and jobs under mpirun (multi_job_test.sh,
# window_move_test.sh, wall_input_test.sh) once they set `work`: the wall's PID goes in `serve`,
# the jobs' in `a` and `b`; `logs` names the files of $work shown when a check fails.
serve="" a="" b=""
logs=${logs:-"serve.out serve.err a.out b.out"}
cleanup() {
  # mpirun and its ranks (killed alone it would leave them running).
  for p in $a $b $serve; do kill -9 $(pgrep -P "$p") "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  [ -n "${KEEP:-}" ] || rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  for f in $logs; do echo "--- $f:"; cat "$work/$f" 2>/dev/null || true; done
  exit 1
}
mpi() { "$MPIEXEC" --oversubscribe --bind-to none --mca mpi_yield_when_idle 1 "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }
scale=${DFBWALL_TIME_SCALE:-1}
timeout=$((8 * scale))
# newest DIR DISPLAY: the newest captured frame's number (0: none yet).
newest() {
  local f
  f=$(ls "$1/$2" 2>/dev/null | grep -E '^frame-[0-9]+\.png$' | sort | tail -1)
  [ -n "$f" ] || { echo 0; return; }
  f=${f#frame-}; echo $((10#${f%.png}))
}
# until_frame DIR DISPLAY N SECONDS: waits until frame N (or later) of DIR is captured.
until_frame() {
  for _ in $(seq $(($4 * 10))); do [ "$(newest "$1" "$2")" -ge "$3" ] && return 0; sleep 0.1; done
  return 1
}
