#!/usr/bin/env bash
# End-to-end tests of the dfbwall executable on real ranks, offscreen. One scenario per call:
#   wall_test.sh equals-single LAYOUT RENDER_RANKS [options for both runs...] [-- wall-only options]
#   wall_test.sh rank0-bytes   LAYOUT RENDER_RANKS MODE
#   wall_test.sh same-frames   LAYOUT RENDER_RANKS
#   wall_test.sh fails         EXPECTED_TEXT NPROCS [dfbwall options...]
#   wall_test.sh window        LAYOUT RENDER_RANKS
#   wall_test.sh dry-run       LAYOUT RENDER_RANKS
#   wall_test.sh rank-dies     LAYOUT RENDER_RANKS
#   wall_test.sh ranks-equal   RANKS [dfbwall options...]   (--image on RANKS ranks == on 1)
#   wall_test.sh preview       LAYOUT RENDER_RANKS MODE [options for both runs...]
#   wall_test.sh scene-bytes   RANKS BRICKS MAX_PERCENT [dfbwall options...]
#   wall_test.sh bricks-whole  BRICKS [dfbwall options...]  (bricked == on 1, 3, 4 ranks, ~ whole)
# Needs DFBWALL (the executable), COMPARE (compare_captures) and MPIEXEC in the environment.
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
mpi() { local n=$1; shift; "$MPIEXEC" -n "$n" --oversubscribe --bind-to none "$@"; }
processes() { "$COMPARE" --info "$1" | cut -d' ' -f1; }  # wall processes of a layout
canvas() { "$COMPARE" --info "$1" | cut -d' ' -f2; }     # its canvas, WxH

scenario=$1; shift
case "$scenario" in
  equals-single)
    layout=$1 renders=$2; shift 2
    w=$(processes "$layout"); size=$(canvas "$layout")
    [ -n "$w" ] && [ -n "$size" ] || { echo "could not read $layout with --dry-run"; exit 1; }
    common=(--frames 3 --spp 2 --seed 11) wallOnly=()
    while [ $# -gt 0 ] && [ "$1" != "--" ]; do common+=("$1"); shift; done
    [ $# -gt 0 ] && shift && wallOnly=("$@")
    mpi $((renders + w)) "$DFBWALL" --wall "$layout" --offscreen --capture "$work/cap" --quiet "${common[@]}" ${wallOnly[@]+"${wallOnly[@]}"}
    mpi 1 "$DFBWALL" --size "$size" --image "$work/full.png" --quiet "${common[@]}"
    "$COMPARE" "$layout" "$work/cap" "$work/full.png" 3
    ;;
  rank0-bytes)
    layout=$1 renders=$2 mode=$3
    w=$(processes "$layout"); size=$(canvas "$layout")
    mpi $((renders + w)) "$DFBWALL" --wall "$layout" --offscreen --mode "$mode" --renderer pattern \
      --frames 4 --stats "$work/stats.json" --quiet
    # JSON Lines: one object per line, frames, ranks, then the summary.
    values=$(grep -o '"rank0_pixel_bytes_received":[0-9]*' "$work/stats.json" | cut -d: -f2 | sort -u)
    frames=$(grep -c '^{"frame":' "$work/stats.json")
    [ "$frames" -eq 4 ] || { echo "stats have $frames frames, expected 4"; exit 1; }
    if [ "$mode" = route ]; then expected=0; else expected=$(( ${size%x*} * ${size#*x} * 4 )); fi
    [ "$values" = "$expected" ] || { echo "rank0_pixel_bytes_received: '$values', expected $expected every frame"; exit 1; }
    tail -n 1 "$work/stats.json" | grep -q '^{"summary":.*"median_frame_ms"' || { echo "no summary in the stats"; exit 1; }
    # One MPI message per piece, however large (gather mode sends whole displays): never cut up.
    pieces=$(grep -o '"wall_pieces":[0-9]*' "$work/stats.json" | cut -d: -f2 | tr '\n' ' ')
    messages=$(grep -o '"wall_messages":[0-9]*' "$work/stats.json" | cut -d: -f2 | tr '\n' ' ')
    [ -n "${pieces// /}" ] && [ "${pieces%% *}" -gt 0 ] && [ "$pieces" = "$messages" ] \
      || { echo "wall_pieces per frame '$pieces', wall_messages '$messages': expected equal"; exit 1; }
    echo "$mode: rank 0 received $expected pixel bytes in each of 4 frames; pieces = messages ($pieces)"
    ;;
  preview)
    # The whole-wall preview assembled on rank 0 from tiles shrunk on their owners equals the
    # box filter of a single-process render; its bytes are counted apart: each tile's cells and
    # a 24-byte header (the factor follows the canvas: these small walls are their own preview),
    # and in route mode rank 0 still receives no pixel of the frame itself.
    layout=$1 renders=$2 mode=$3; shift 3
    w=$(processes "$layout"); size=$(canvas "$layout")
    common=(--frames 3 --spp 2 --seed 11 "$@")
    mpi $((renders + w)) "$DFBWALL" --wall "$layout" --offscreen --mode "$mode" \
      --preview "$work/preview.png" --stats "$work/stats.json" --quiet "${common[@]}"
    mpi 1 "$DFBWALL" --size "$size" --image "$work/full.png" --quiet "${common[@]}"
    "$COMPARE" --preview "$layout" "$work/preview.png" "$work/full.png"
    /usr/bin/python3 - "$work/stats.json" "$mode" "$size" "$work/preview.png" "${common[@]}" <<'PY'
import json, struct, sys
w, h = map(int, sys.argv[3].split('x'))
pw, ph = struct.unpack('>II', open(sys.argv[4], 'rb').read()[16:24])  # the PNG's IHDR
f = next(f for f in (1 << k for k in range(16)) if -(-w // f) == pw and -(-h // f) == ph)
args = sys.argv[5:]
tile = int(args[args.index('--tile-size') + 1]) if '--tile-size' in args else 64
# Every tile's message: a header and the cells it touches (the most a frame can send; route mode
# renders only the tiles some display shows).
most = 0
for ty in range(0, h, tile):
    for tx in range(0, w, tile):
        x1, y1 = min(tx + tile, w), min(ty + tile, h)
        most += 24 + 4 * ((x1 + f - 1) // f - tx // f) * ((y1 + f - 1) // f - ty // f)
frames = [l for l in map(json.loads, open(sys.argv[1])) if 'frame' in l]
assert len(frames) == 3, f'{len(frames)} frame lines'
for f_ in frames:
    p, rank0 = f_['preview_bytes'], f_['rank0_pixel_bytes_received']
    assert 0 < p <= most, f'frame {f_["frame"]}: preview {p} bytes, at most {most} expected'
    if sys.argv[2] == 'gather':  # every tile completes every frame
        assert p == most, f'frame {f_["frame"]}: preview {p} bytes, {most} expected'
    if sys.argv[2] == 'route':
        assert rank0 == 0, f'frame {f_["frame"]}: rank 0 received {rank0} pixel bytes'
print(f'preview {pw}x{ph} cells (factor {f}), bytes per frame: {frames[-1]["preview_bytes"]}, '
      f'pieces {frames[-1]["wall_bytes_raw"]}, canvas {w * h * 4}')
PY
    ;;
  same-frames)
    layout=$1 renders=$2
    w=$(processes "$layout")
    mpi $((renders + w)) "$DFBWALL" --wall "$layout" --offscreen --renderer pattern --frames 5 \
      --capture "$work/cap" --capture-every 2 --quiet
    expected="frame-000002.png frame-000004.png frame-000005.png"
    for dir in "$work"/cap/*/; do
      got=$(ls "$dir" | tr '\n' ' ' | sed 's/ $//')
      [ "$got" = "$expected" ] || { echo "$dir holds '$got', expected '$expected'"; exit 1; }
    done
    [ -f "$work/cap/wall-000002.png" ] && [ -f "$work/cap/wall-000004.png" ] && [ -f "$work/cap/wall-000005.png" ] \
      || { echo "wall previews missing"; ls "$work/cap"; exit 1; }
    [ -z "$(find "$work/cap" -name '*.partial' -o -name '*.tmp*')" ] || { echo "temporary files left"; exit 1; }
    echo "every display captured frames 2, 4 and 5, with previews"
    ;;
  fails)
    text=$1 n=$2; shift 2
    start=$(date +%s)
    set +e
    output=$(timeout 30 "$MPIEXEC" -n "$n" --oversubscribe --bind-to none "$DFBWALL" "$@" 2>&1)
    code=$?
    set -e
    elapsed=$(( $(date +%s) - start ))
    echo "$output"
    [ "$code" -ne 0 ] || { echo "FAIL: exit code 0 for bad input"; exit 1; }
    [ "$code" -ne 124 ] || { echo "FAIL: hung (killed after 30 s)"; exit 1; }
    grep -qF -- "$text" <<<"$output" || { echo "FAIL: the message lacks '$text'"; exit 1; }
    [ "$(grep -c 'dfbwall: error' <<<"$output")" -eq 1 ] || { echo "FAIL: expected exactly one error line"; exit 1; }
    grep -q 'core dumped\|Segmentation\|Aborted' <<<"$output" && { echo "FAIL: crashed"; exit 1; }
    echo "exit $code after ${elapsed}s with the expected message"
    ;;
  window)
    layout=$1 renders=$2
    w=$(processes "$layout")
    mpi $((renders + w)) "$DFBWALL" --wall "$layout" --offscreen --capture "$work/off" --frames 2 --quiet
    # A server number of its own, so a concurrent Xvfb test elsewhere cannot take the same one.
    xvfb-run -a -n $((300 + RANDOM % 500)) -s "-screen 0 1280x1024x24 -noreset" \
      "$MPIEXEC" -n $((renders + w)) --oversubscribe --bind-to none -x DISPLAY -x XAUTHORITY \
      "$DFBWALL" --wall "$layout" --capture "$work/win" --frames 2 --quiet
    # The window's pixels are read back from the X server: they must equal the offscreen frame.
    "$COMPARE" "$layout" "$work/win" "$work/off/wall-000002.png" 2
    ;;
  dry-run)
    layout=$1 renders=$2
    w=$(processes "$layout"); size=$(canvas "$layout")
    output=$(mpi $((renders + w)) "$DFBWALL" --wall "$layout" --dry-run --tile-size 64)
    echo "$output"
    grep -q "canvas $size, " <<<"$output" || { echo "FAIL: no canvas $size"; exit 1; }
    grep -q "ranks: 0..$((renders - 1)) render, $renders..$((renders + w - 1)) wall" <<<"$output" \
      || { echo "FAIL: rank roles"; exit 1; }
    # Every listed tile names an owner among the render ranks.
    owners=$(grep '^display ' <<<"$output" | grep -o '@r[0-9]*' | sort -u | tr -d '@r')
    for o in $owners; do [ "$o" -lt "$renders" ] || { echo "FAIL: owner rank $o is not a render rank"; exit 1; }; done
    [ -n "$owners" ] || { echo "FAIL: no tiles listed"; exit 1; }
    ;;
  rank-dies)
    # Invariant 6: a wall rank killed mid-run ends the job with an error, it does not hang it.
    layout=$1 renders=$2
    w=$(processes "$layout")
    "$MPIEXEC" -n $((renders + w)) --oversubscribe --bind-to none "$DFBWALL" --wall "$layout" \
      --offscreen --renderer pattern --frames 1000000 --quiet --timeout 5 >"$work/log" 2>&1 &
    job=$!
    sleep 2
    victim=$(pgrep -P "$job" -x dfbwall | tail -n 1)
    [ -n "$victim" ] || { echo "FAIL: no rank to kill"; cat "$work/log"; exit 1; }
    kill -9 "$victim"
    start=$(date +%s)
    set +e
    for _ in $(seq 1 60); do kill -0 "$job" 2>/dev/null || break; sleep 0.5; done
    if kill -0 "$job" 2>/dev/null; then kill -9 "$job"; echo "FAIL: job still running 30 s after a rank died"; exit 1; fi
    wait "$job"
    code=$?
    set -e
    [ "$code" -ne 0 ] || { echo "FAIL: exit code 0 after a rank died"; exit 1; }
    echo "job ended with exit $code $(( $(date +%s) - start )) s after rank $victim was killed"
    ;;
  ranks-equal)
    # Image-parallel: any number of ranks renders the picture one rank renders, byte for byte.
    n=$1; shift
    mpi 1 "$DFBWALL" --image "$work/one.png" --quiet "$@"
    mpi "$n" "$DFBWALL" --image "$work/many.png" --quiet "$@"
    cmp "$work/one.png" "$work/many.png" || { echo "FAIL: $n ranks differ from 1 rank"; exit 1; }
    echo "$n ranks wrote the 1-rank image byte for byte ($(stat -c %s "$work/one.png") bytes)"
    ;;
  scene-bytes)
    # Memory: with --bricks BRICKS on RANKS ranks every render rank's scene_bytes (the brick data
    # it holds, from --stats) is at most MAX_PERCENT of the whole scene's (one brick, one rank).
    n=$1 bricks=$2 percent=$3; shift 3
    mpi "$n" "$DFBWALL" --bricks "$bricks" --stats "$work/split.json" --quiet "$@"
    mpi 1 "$DFBWALL" --bricks 1 --stats "$work/whole.json" --quiet "$@"
    /usr/bin/python3 - "$work/split.json" "$work/whole.json" "$n" "$percent" <<'PY'
import json, sys
def held(path):
    return [l['scene_bytes'] for l in map(json.loads, open(path)) if l.get('role') == 'render']
split, (whole,), n, percent = held(sys.argv[1]), held(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
assert len(split) == n, f'{len(split)} render ranks in the stats, expected {n}'
shares = [100 * b / whole for b in split]
print('scene_bytes per rank: ' + ', '.join(f'{b:.0f} ({s:.1f}%)' for b, s in zip(split, shares)) +
      f' of {whole:.0f} bytes (the whole scene)')
assert whole > 0 and min(split) > 0, 'a rank holds nothing'
assert max(shares) <= percent, f'a rank holds {max(shares):.1f}% of the scene, more than {percent}%'
PY
    ;;
  bricks-whole)
    # Data-parallel with every shading ray (AO and shadows across bricks, --ghost reach):
    # --bricks BRICKS writes the same bytes on 1, 3 and 4 ranks and with --replication 2, and
    # equals --bricks 1 within 1e-4 per channel (linear .pfm); --ghost layer, whose shading rays
    # see only the brick, does not (so the scene does cast shadows and AO across bricks).
    bricks=$1; shift
    mpi 1 "$DFBWALL" --bricks "$bricks" --image "$work/one.pfm" --quiet "$@"
    for run in "3" "4" "4 --replication 2"; do
      read -r n more <<<"$run"
      # shellcheck disable=SC2086
      mpi "$n" "$DFBWALL" --bricks "$bricks" $more --image "$work/many.pfm" --quiet "$@"
      cmp "$work/one.pfm" "$work/many.pfm" || { echo "FAIL: --bricks $bricks on $run ranks differs from 1 rank"; exit 1; }
    done
    mpi 1 "$DFBWALL" --bricks 1 --image "$work/whole.pfm" --quiet "$@"
    mpi 1 "$DFBWALL" --bricks "$bricks" --ghost layer --image "$work/layer.pfm" --quiet "$@"
    reach=$("$root/scripts/pfm-diff" "$work/whole.pfm" "$work/one.pfm" | cut -d' ' -f2)
    layer=$("$root/scripts/pfm-diff" "$work/whole.pfm" "$work/layer.pfm" | cut -d' ' -f2)
    echo "--bricks $bricks on 1, 3, 4 ranks and replication 2: the same bytes; largest difference" \
      "per channel from --bricks 1: $reach (--ghost layer: $layer)"
    awk -v r="$reach" 'BEGIN {exit !(r <= 1e-4)}' || { echo "FAIL: --bricks $bricks differs from --bricks 1 by $reach > 1e-4"; exit 1; }
    awk -v l="$layer" 'BEGIN {exit !(l > 1e-3)}' || { echo "FAIL: --ghost layer differs by only $layer: nothing crosses bricks"; exit 1; }
    ;;
  *) echo "unknown scenario $scenario"; exit 2 ;;
esac
