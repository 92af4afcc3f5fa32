# The `pixelcost` figure of scripts/bench (sourced by it; uses its helpers and variables): CPU
# nanoseconds per delivered pixel on one host, after rendering on the render side and after the
# wire (GL excluded) on the wall side, per stage, three ways:
#  1. the app: the 2x2 1080p wall, 2 render + 4 wall ranks over shared memory; the per-pixel
#     stages are thread-CPU timers (base/Timing.h), and the rest of each process's CPU over the
#     frames is reported beside them. Each figure is a difference between a long and a short run
#     (steady state: the first frames' page faults on fresh display images and buffers, tens of
#     ms here, cancel out) ("other": the messenger's MPI and inbox threads, MPI's
#     copies, waiting) — render ranks less their render() calls, wall ranks less their main
#     thread (waits, swap barrier, GL calls) and the GL driver's threads;
#  2. pixel_cost_bench: the same stages' code on one thread, thread CPU clock, same-host and
#     other-host links (plane-delta + Snappy), pattern RGBA8 and noisy float tiles;
#  3. callgrind instruction counts of 2's stages (repeatable whatever the machine's load).
# fig_cluster runs it too (its single-host part). The goal: <= 5 ns per side.

fig_pixelcost() {
  # Frames of the short and the long run of each renderer.
  local short=3 long=9 ptshort=2 ptlong=5 reps=2 benchFrames=5
  [ $quick = 1 ] && long=6 ptlong=4 reps=1 benchFrames=2
  local pixels=$((3840 * 2160)) appRows="" benchRows="" irRows="" dat="$work/pc.dat"
  pixelcost_goals=()
  : >"$dat"
  echo "== pixelcost (one host): CPU ns per delivered pixel, 2x2 1080p wall; load $(cut -d' ' -f1-3 /proc/loadavg)"
  local rep v r f fs fl len s
  for rep in $(seq "$reps"); do
    for v in "pattern $short $long" "pathtracer $ptshort $ptlong"; do
      read -r r fs fl <<<"$v"
      for len in short long; do
        f=$fs
        [ $len = long ] && f=$fl
        mpi 6 "$dfbwall" --wall "$wall2x2" --offscreen --scene "$orbit_scene" --orbit $orbit --renderer "$r" \
          --spp 1 --frames "$f" --quiet --stats "$work/pc-$r-$len-$rep.json"
      done
    done
  done
  for v in "pattern $short $long" "pathtracer $ptshort $ptlong"; do
    read -r r fs fl <<<"$v"
    local n=$(((fl - fs) * reps)) stages="" role
    ns_of() {  # ns_of ROLE FIELD: milliseconds of the long runs less the short ones, in ns/pixel
      local file sign
      for file in "$work"/pc-$r-*.json; do
        sign=1
        case "$file" in *-short-*) sign=-1 ;; esac
        echo "$sign $(stage_sum "$file" "$1" "$2")"
      done | awk -v p=$pixels -v n=$n '{t += $1 * $2} END {printf "%.4g", t * 1e6 / (n * p)}'
    }
    local renderStages=0 wallStages=0 x
    for s in tile_unpack tile_operation tone_map cut send; do
      x=$(ns_of render $s)
      stages+="${stages:+, }\"render.$s\": $x"
      renderStages=$(awk -v a="$renderStages" -v b="$x" 'BEGIN {printf "%.4g", a + b}')
      printf '"%s render.%s" %s\n' "$r" "$s" "$x" >>"$dat"
    done
    local processR renderCpu otherR
    processR=$(ns_of render process_cpu)
    renderCpu=$(ns_of render render_cpu)
    otherR=$(awk -v a="$processR" -v b="$renderCpu" -v c="$renderStages" 'BEGIN {printf "%.4g", a - b - c}')
    printf '"%s render.other" %s\n' "$r" "$otherR" >>"$dat"
    for s in piece_unpack assemble; do
      x=$(ns_of wall $s)
      stages+=", \"wall.$s\": $x"
      wallStages=$(awk -v a="$wallStages" -v b="$x" 'BEGIN {printf "%.4g", a + b}')
      printf '"%s wall.%s" %s\n' "$r" "$s" "$x" >>"$dat"
    done
    local processW mainW glW otherW
    processW=$(ns_of wall process_cpu)
    mainW=$(ns_of wall main_thread_cpu)
    glW=$(ns_of wall gl_threads_cpu)
    otherW=$(awk -v a="$processW" -v b="$mainW" -v c="$glW" -v d="$wallStages" 'BEGIN {printf "%.4g", a - b - c - d}')
    printf '"%s wall.other" %s\n' "$r" "$otherW" >>"$dat"
    local renderAll wallAll
    renderAll=$(awk -v a="$renderStages" -v b="$otherR" 'BEGIN {printf "%.4g", a + b}')
    wallAll=$(awk -v a="$wallStages" -v b="$otherW" 'BEGIN {printf "%.4g", a + b}')
    echo "  app, $r: render side $renderStages ns/px in the stages + $otherR other = $renderAll;" \
      "wall side $wallStages + $otherW other = $wallAll (render() $renderCpu, wall main thread $mainW, GL threads $glW)"
    appRows+="${appRows:+,}
    {\"renderer\": \"$r\", \"frames\": $n, \"frames_short_long\": [$fs, $fl], \"stages\": {$stages},
     \"render.stages_total\": $renderStages, \"render.other\": $otherR, \"render.total\": $renderAll,
     \"render.process_cpu\": $processR, \"render.render_cpu\": $renderCpu,
     \"wall.stages_total\": $wallStages, \"wall.other\": $otherW, \"wall.total\": $wallAll,
     \"wall.process_cpu\": $processW, \"wall.main_thread_cpu\": $mainW, \"wall.gl_threads_cpu\": $glW}"
    local side
    for side in "render $renderStages $renderAll" "wall $wallStages $wallAll"; do
      set -- $side
      pixelcost_goals+=("<= 5 ns CPU per delivered pixel, app on one host, $r, $1 side: stages $2, with the rest of the process $3, $(awk -v a="$2" -v b="$3" 'BEGIN {print (a <= 5 ? "stages met" : "stages missed") ", " (b <= 5 ? "total met" : "total missed")}')")
    done
  done

  # The stages on one thread: thread CPU clock, then instructions.
  "$build/bench/pixel_cost_bench" --frames "$benchFrames" --json "$work/pc-bench.json" | tee "$work/pc-bench.txt"
  benchRows=$(sed -n '/"results": \[/,/^ \]/p' "$work/pc-bench.json" | sed '1d;$d')
  local content link
  if command -v valgrind >/dev/null; then
    for content in pattern float-noisy; do
      for link in same-host other-host; do
        local out="$work/pc-callgrind-$content-$link.out"
        # Frame 0 (warm-up) is collected too: 2 frames of instructions.
        valgrind --tool=callgrind --callgrind-out-file="$out" --collect-atstart=no \
          --toggle-collect='*::stage*' "$build/bench/pixel_cost_bench" --frames 1 \
          --content "$content" --link "$link" >/dev/null 2>"$work/pc-callgrind.log"
        local irs=""
        for s in TileOperation ToneMap Cut Seal Open PieceUnpack Assemble; do
          local ir
          ir=$({ callgrind_annotate --inclusive=yes --threshold=100 "$out" 2>/dev/null || true; } |
            awk -v f="::stage$s(" 'index($0, f) {gsub(",", "", $1); print $1; exit}')
          ir=$(awk -v i="${ir:-0}" -v p=$pixels 'BEGIN {printf "%.4g", i / (2 * p)}')
          irs+="${irs:+, }\"$s\": $ir"
        done
        echo "  callgrind, $content, $link: instructions per delivered pixel {$irs}"
        irRows+="${irRows:+,}
    {\"content\": \"$content\", \"link\": \"$link\", \"instructions_per_delivered_pixel\": {$irs}}"
      done
    done
  fi

  goals_json ${pixelcost_goals[@]+"${pixelcost_goals[@]}"}
  cat >"$results/pixelcost.json" <<EOF
{"figure": "pixelcost", "machine": $machine, "load_average_at_start": "$(cut -d' ' -f1-3 /proc/loadavg)",
 "setup": {"wall": "2x2 x 1920x1080 (3840x2160), one host, 2 render + 4 wall ranks, shared memory (nothing compressed)",
           "frames_short_and_long_run": {"pattern": [$short, $long], "pathtracer": [$ptshort, $ptlong]}, "runs": $reps,
           "steady_state": "every app figure is (long runs - short runs) / (frames difference x 3840 x 2160): start-up costs cancel",
           "unit": "CPU ns per delivered pixel (3840 x 2160 per frame), summed over the side's ranks and threads",
           "stages": "thread CPU clock per stage (base/Timing.h); render side after render(), wall side after the wire",
           "other": "render: process CPU over the frames - render() CPU - stages; wall: process CPU - main thread (waits, swap barrier, GL calls) - GL driver threads (llvmpipe) - stages. Mostly the messenger's MPI and inbox threads (MPI copies, polling, decompression, dispatch)"},
 "goals": [$goals_json],
 "app": [$appRows
 ],
 "pixel_cost_bench": [
$benchRows
 ],
 "callgrind": [$irRows
 ]}
EOF
  plot pixelcost <(cat <<EOF
set title "CPU ns per delivered pixel on one host, per stage (app; goal <= 5 per side)"
set style data histogram; set style fill solid 0.6; set xtics rotate by -30 font ",8"; set yrange [0:*]
set ylabel "ns per delivered pixel, summed over ranks and threads"; set key off
plot '$dat' using 2:xtic(1) lc rgb "#3070b0"
EOF
)
}
