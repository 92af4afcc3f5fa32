# The `cluster` figure of scripts/bench (sourced by it; uses its helpers and variables):
# route vs gather on the 2x2 1080p wall across emulated hosts (scripts/cluster) with 1 Gbit/s
# links, 2 and 4 render hosts of one rank each, pattern (uncompressed and compressed) and path
# tracer; link utilisation; bytes on the wire vs raw; and, on one host, CPU nanoseconds per
# delivered pixel per stage (fig_pixelcost, bench/pixelcost.sh). Needs root (network namespaces).

# Median over the frames of stats files (frame 1 left out) of FIELD_A / FIELD_B * SCALE.
ratio_of() {
  local a=$1 b=$2 scale=$3 f
  shift 3
  for f in "$@"; do paste <(frames_of "$f" "$a") <(frames_of "$f" "$b"); done |
    awk -v s="$scale" '$2 > 0 {print $1 / $2 * s}' | median
}

cluster_ids=()
cluster_down_all() {
  local i
  for i in ${cluster_ids[@]+"${cluster_ids[@]}"}; do
    "$root/scripts/cluster" down --id "$i" >/dev/null 2>&1 || true
  done
  cluster_ids=()
}

fig_cluster() {
  local frames=6 ptframes=4 reps=2
  [ $quick = 1 ] && frames=4 ptframes=3 reps=1
  local hostsWall="$root/configs/walls/2x2-1080p-hosts.toml" linkBytes=125000000  # 1 Gbit/s
  local counts=(2 4) mpiruns=() loadAtStart
  loadAtStart=$(cut -d' ' -f1-3 /proc/loadavg)
  echo "== cluster: 2x2 wall of 1920x1080 on 2 wall hosts, 2 or 4 render hosts (1 rank each), 1 Gbit/s links; load $(cut -d' ' -f1-3 /proc/loadavg)"
  [ "$(id -u)" -eq 0 ] || { echo "bench: the cluster figure needs root (scripts/cluster)" >&2; return 1; }
  trap cluster_down_all EXIT
  local n
  for n in "${counts[@]}"; do
    "$root/scripts/cluster" up --id auto --holder $$ --build "$build" --wall "$hostsWall" \
      --render-hosts "$n" --rate 1gbit >"$work/cluster-up-$n.txt"
    cluster_ids+=("$(sed -n 's/^cluster \([0-9]*\):.*/\1/p' "$work/cluster-up-$n.txt")")
    mpiruns+=("$(sed -n 's/^run: \([^ ]*\) .*/\1/p' "$work/cluster-up-$n.txt")")
  done
  # Variants: name, renderer, extra option ("-": none), frames, scene ("-": the Cornell orbit).
  # Pattern uncompressed is the goals' case.
  local variants=("pattern-raw pattern --no-compress $frames -" "pattern pattern - $frames -"
                  "pathtracer pathtracer - $ptframes -" "scivis scivis - $ptframes builtin:wavelet")
  local rep i v name r opt f mode extra sc
  for rep in $(seq "$reps"); do
    for v in "${variants[@]}"; do
      read -r name r opt f sc <<<"$v"
      extra=()
      [ "$opt" = - ] || extra=("$opt")
      [ "$sc" = - ] && sc=$orbit_scene
      for i in "${!counts[@]}"; do
        for mode in route gather; do  # interleaved
          # A generous deadline: a scivis frame of this wall took 17-40 s on a loaded machine,
          # and the first one (scene set-up included) passed the default 60 s once. A run that
          # fails anyway is reported and left out; the other runs still count.
          "${mpiruns[$i]}" "$dfbwall" --wall "$hostsWall" --offscreen --scene "$sc" \
            --orbit $orbit --renderer "$r" --spp 1 --frames "$f" --mode "$mode" --quiet \
            --timeout 300 ${extra[@]+"${extra[@]}"} \
            --stats "$work/cl-$name-${counts[$i]}-$mode-$rep.json" ||
            echo "bench: cluster run $name, ${counts[$i]} render hosts, $mode, run $rep failed; left out" >&2
        done
      done
    done
  done
  cluster_down_all

  local rows="" dat="$work/cl.dat" util="$work/cl-util.dat" bytes="$work/cl-bytes.dat" goals=()
  : >"$dat"
  : >"$util"
  : >"$bytes"
  for v in "${variants[@]}"; do
    read -r name r opt f sc <<<"$v"
    for n in "${counts[@]}"; do
      local fps=()
      for mode in route gather; do
        local files=("$work"/cl-$name-$n-$mode-*.json)
        local med mad cnt fr wire raw senders u
        read -r med mad cnt < <(pooled frame_ms "${files[@]}" | medmad)
        fr=$(awk -v m="$med" 'BEGIN {printf "%.4g", (m > 0) ? 1000 / m : 0}')
        fps+=("$fr")
        wire=$(pooled wall_bytes_sent "${files[@]}" | median)
        raw=$(pooled wall_bytes_raw "${files[@]}" | median)
        # Link utilisation: the pieces' wire bytes per second over the summed uplinks of the
        # hosts that send them (route: every render host; gather: render1, which relays).
        senders=$n
        [ "$mode" = gather ] && senders=1
        u=$(ratio_of wall_bytes_sent frame_ms "$(awk -v s=$senders -v l=$linkBytes 'BEGIN {print 1000 / (s * l)}')" "${files[@]}")
        u=$(awk -v u="$u" 'BEGIN {printf "%.3g", u}')
        rows+="${rows:+,}
    {\"renderer\": \"$r\", \"compression\": $([ "$opt" = --no-compress ] && echo false || echo true), \"render_hosts\": $n, \"mode\": \"$mode\", \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"fps\": $fr,
     \"wall_bytes_wire_per_frame\": $wire, \"wall_bytes_raw_per_frame\": $raw, \"wire_over_raw\": $(awk -v a="$wire" -v b="$raw" 'BEGIN {printf "%.4g", (b > 0) ? a / b : 0}'), \"sending_hosts\": $senders, \"link_utilisation\": $u}"
        echo "  $name, $n render hosts, $mode: $fr fps (median $med ms, MAD $mad), wire $wire of raw $raw bytes/frame, link utilisation $u"
        printf '"%s %dh %s" %s\n' "$name" "$n" "$mode" "$u" >>"$util"
        if [ "$mode" = route ] && [ "$n" = 2 ]; then printf '"%s" %s %s\n' "$name" "$wire" "$raw" >>"$bytes"; fi
      done
      local ratio
      ratio=$(awk -v a="${fps[0]}" -v b="${fps[1]}" 'BEGIN {printf "%.3g", (b > 0) ? a / b : 0}')
      rows+=",
    {\"variant\": \"$name\", \"render_hosts\": $n, \"route_over_gather_fps\": $ratio}"
      echo "  $name, $n render hosts: route/gather = ${ratio}x"
      printf '"%s %dh" %s %s %s\n' "$name" "$n" "${fps[0]}" "${fps[1]}" "$ratio" >>"$dat"
      if [ "$name" = pattern-raw ]; then
        local want=2
        [ "$n" = 4 ] && want=3
        goals+=("route >= ${want}x gather, pattern uncompressed, $n render hosts: ${ratio}x, $(awk -v a="$ratio" -v w=$want 'BEGIN {print (a >= w) ? "met" : "missed"}')")
      fi
    done
  done
  local routeUtil
  routeUtil=$(grep '^"pattern-raw [0-9]h route"' "$util" | awk '{print $NF}' | sort -g | tail -1)
  goals+=("route link utilisation >= 0.8, pattern uncompressed: best $routeUtil, $(awk -v u="$routeUtil" 'BEGIN {print (u >= 0.8) ? "met" : "missed"}')")

  # One host: CPU per delivered pixel, per stage (bench/pixelcost.sh, also its own figure).
  fig_pixelcost
  goals+=(${pixelcost_goals[@]+"${pixelcost_goals[@]}"})

  goals_json ${goals[@]+"${goals[@]}"}
  cat >"$results/cluster.json" <<EOF
{"figure": "cluster", "machine": $machine, "load_average_at_start": "$loadAtStart", "load_average_at_end": "$(cut -d' ' -f1-3 /proc/loadavg)",
 "setup": {"wall": "2x2 x 1920x1080 (3840x2160); wall1 drives the top row, wall2 the bottom (one wall rank per display)",
           "render_hosts": [2, 4], "render_ranks_per_host": 1, "links": "tc tbf 1gbit each way per host (scripts/cluster)",
           "transport": "OpenMPI TCP between network namespaces of one machine with $(nproc) cores for every rank",
           "spp": 1, "orbit_degrees_per_frame": $orbit, "frames_per_run": {"pattern": $frames, "pathtracer": $ptframes, "scivis": $ptframes}, "scenes": {"pattern, pathtracer": "Cornell box orbit", "scivis": "builtin:wavelet"}, "runs": $reps,
           "link_utilisation": "wall_bytes_sent per second / (sending hosts x 125e6 B/s); route: every render host sends, gather: render1 relays",
           "cpu_per_pixel": "one host: see pixelcost.json (thread CPU per stage, the rest of each process, pixel_cost_bench, callgrind)"},
 "goals": [$goals_json],
 "results": [$rows
 ]}
EOF
  gnuplot -e "set terminal pngcairo size 1400,560 noenhanced; set output '$results/cluster.png'" <(cat <<EOF
set multiplot layout 1,3 title "2x2 1080p wall over 1 Gbit/s links (emulated hosts, median over the orbit)"
set style data histogram; set style fill solid 0.6; set key top right; set xtics rotate by -30 font ",8"
set ylabel "frames per second"; set yrange [0:*]
plot '$dat' using 2:xtic(1) title "route" lc rgb "#3070b0", '' using 3 title "gather" lc rgb "#c08030"
set ylabel "link utilisation (sending hosts' uplinks)"; set yrange [0:1.05]
plot '$util' using 2:xtic(1) title "wire bytes/s / uplink capacity" lc rgb "#3070b0", 0.8 with lines dt 2 title "goal for route"
set ylabel "MB per frame to the walls (route, 2 render hosts)"; set logscale y; set yrange [0.1:*]
plot '$bytes' using (\$2 / 1e6):xtic(1) title "on the wire" lc rgb "#3070b0", '' using (\$3 / 1e6) title "raw" lc rgb "#c08030"
unset multiplot
EOF
)
  trap - EXIT
}
