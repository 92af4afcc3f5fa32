# Figure "dataparallel" of scripts/bench (sourced by it; uses its helpers and variables): the
# scivis renderer data-parallel through the DFB (--bricks N --replication K).
#  1. Strong scaling 1 -> 2 -> 4 ranks of a 256^3 wavelet (faint volume + two isosurfaces, AO)
#     cut into 4 bricks, with image-parallel (--bricks 0, whole scene on every rank) beside it.
#  2. Compositing overhead per frame on 2 and 4 ranks: composite_ms / frame_ms as the statistics
#     report it, and (frame_ms - render_ms) / frame_ms, everything but the slowest rank's rendering.
#  3. Memory: scene_bytes and peak RSS per rank on 1, 2, 4 ranks with --bricks 4 against the
#     whole scene on every rank (--bricks 1 --replication RANKS), ambient occlusion on and off,
#     for both ghost modes: --ghost reach (2 voxels densely around each brick, and as far as AO
#     and shadow rays reach the macrocells holding an isovalue, sparsely; images equal the whole
#     scene's) and --ghost layer (2 voxels; AO near brick faces differs, no shadows across them).
#  4. Mixed vs pure data-parallel on a skewed scene (a dense, translucent particle cluster inside
#     brick 0; the rest of the domain is an invisible volume): --bricks 4 on 4 ranks with
#     --replication 2 vs 1.
# One thread per rank (--threads 1), so 1 rank = 1 core, 2 ranks = 2 cores, and 4 ranks on this
# 2-core machine are oversubscribed 2x. Variants run interleaved (A B A B ...); every frame of
# --orbit is a new camera (a new epoch); medians and MADs leave each run's first frame out.

# "frame_ms render_ms composite_ms" per frame of a stats file, frame 1 left out.
dp_frames() {
  sed -n 's/.*"frame": *\([0-9]*\), *"frame_ms": *\([-0-9.e]*\), *"render_ms": *\([-0-9.e]*\), *"composite_ms": *\([-0-9.e]*\).*/\1 \2 \3 \4/p' "$1" |
    awk '$1 > 1 {print $2, $3, $4}'
}
# FIELD of every render rank's line of a stats file, one per line, in rank order.
dp_ranks() { grep '"role": *"render"' "$1" | grep -o "\"$2\": *[-0-9.e+]*" | sed 's/.*: *//'; }
dp_json_list() { paste -sd, - | sed 's/^/[/; s/$/]/'; }

fig_dataparallel() {
  local size=800x600 frames=6 reps=2 res=256 memsize=200x150
  [ $quick = 1 ] && size=400x300 frames=4 reps=1
  local w=${size%x*} h=${size#*x} step=3 load0
  load0=$(cut -d' ' -f1-3 /proc/loadavg)
  echo "== dataparallel: scivis --bricks, ${res}^3 wavelet, $size, 1 thread per rank (4 ranks on $(nproc) cores: oversubscribed)"

  # The scenes: the wavelet of builtin:wavelet at res^3 (AO 1 ray up to 0.3 = 15% of the
  # domain, as the built-in), the same without AO, and the skewed particle scene.
  local wave="$work/dp-wavelet.toml" waveNoAo="$work/dp-wavelet-noao.toml" skew="$work/dp-skew.toml"
  cat >"$wave" <<EOF
[camera]
position = [2.3, 1.5, 2.9]
look_at = [0.0, -0.05, 0.0]
fov = 38.0
[environment]
type = "gradient"
bottom = [0.02, 0.02, 0.03]
top = [0.12, 0.14, 0.22]
[materials.outer]
type = "diffuse"
color = [0.55, 0.7, 1.0]
opacity = 0.18
specular = 0.4
[materials.core]
type = "diffuse"
color = [1.0, 0.55, 0.2]
specular = 0.3
[[volumes]]
name = "wavelet"
source = "wavelet"
dims = [$res, $res, $res]
transfer_function = { preset = "cool-warm", range = [37.0, 277.0], opacity = [[37.0, 0.0], [190.0, 0.0], [277.0, 0.04]] }
[[isosurfaces]]
volume = "wavelet"
values = [160.0, 215.0]
materials = ["outer", "core"]
[scivis]
ao_samples = 1
ao_distance = 0.3
EOF
  sed 's/^ao_samples = .*/ao_samples = 0/' "$wave" >"$waveNoAo"
  # Skewed: 4 bricks of the cube [-1, 1]^3 are the quarter columns x<0|x>0 by y<0|y>0 (ids 0..3
  # in k-d order). A million translucent particles (opacity 0.35, 2 AO rays) clump inside brick
  # 0 (x, y < 0); an invisible 32^3 volume only spans the domain, so bricks 1-3 are nearly empty.
  cat >"$skew" <<EOF
[camera]
position = [0.2, 0.2, 1.9]
look_at = [-0.5, -0.5, 0.0]
fov = 40.0
[environment]
type = "gradient"
bottom = [0.02, 0.02, 0.03]
top = [0.12, 0.14, 0.22]
[materials.dust]
type = "diffuse"
color = [0.9, 0.8, 0.6]
opacity = 0.35
specular = 0.3
[[volumes]]
name = "domain"
source = "wavelet"
dims = [32, 32, 32]
visible = false
transfer_function = { preset = "cool-warm", range = [37.0, 277.0] }
[[particles]]
name = "cluster"
material = "dust"
generator = "clusters"
count = 1000000
seed = 3
center = [-0.5, -0.5, 0.0]
size = 0.9
radius = 0.006
[scivis]
ao_samples = 2
ao_distance = 0.1
EOF

  local run=("$dfbwall" --renderer scivis --threads 1 --quiet)
  # 1 + 2: strong scaling, data-parallel (4 bricks) and image-parallel, interleaved.
  local counts=(1 2 4) rep n b
  for rep in $(seq "$reps"); do
    for n in "${counts[@]}"; do
      for b in 4 0; do
        mpi "$n" "${run[@]}" --scene "$wave" --size "$size" --bricks $b --orbit $step \
          --frames "$frames" --stats "$work/dp-scale-b$b-n$n-$rep.json"
      done
    done
  done
  # 4: skewed scene, replication 1 vs 2 on 4 ranks, interleaved.
  local k
  for rep in $(seq "$reps"); do
    for k in 1 2; do
      mpi 4 "${run[@]}" --scene "$skew" --size "$size" --bricks 4 --replication $k --orbit $step \
        --frames "$frames" --stats "$work/dp-skew-k$k-$rep.json"
    done
  done
  # 3: memory, one small frame per run: 4 bricks (both ghost modes) vs the whole scene on every
  # rank, AO on/off.
  local ao scene g
  for ao in on off; do
    scene=$wave
    [ $ao = on ] || scene=$waveNoAo
    for n in "${counts[@]}"; do
      for g in reach layer; do
        mpi "$n" "${run[@]}" --scene "$scene" --size $memsize --bricks 4 --ghost $g --frames 1 \
          --stats "$work/dp-mem-$ao-b4$g-n$n.json"
      done
      mpi "$n" "${run[@]}" --scene "$scene" --size $memsize --bricks 1 --replication "$n" \
        --frames 1 --stats "$work/dp-mem-$ao-b1-n$n.json"
    done
  done
  # The AO seams of --ghost layer: the largest difference per channel (linear radiance, .pfm)
  # of 4 bricks against the unbricked render, both ghost modes, one rank, same seed, shadows
  # off (AO alone: --ghost layer also loses the shadows across bricks), $seamFrames frames
  # accumulated.
  local seam="$work/dp-wavelet-seam.toml" seamFrames=8
  sed 's/^ao_distance = .*/&\nshadows = false/' "$wave" >"$seam"
  mpi 1 "${run[@]}" --scene "$seam" --size $memsize --bricks 1 --frames $seamFrames \
    --image "$work/dp-seam-whole.pfm"
  for g in reach layer; do
    mpi 1 "${run[@]}" --scene "$seam" --size $memsize --bricks 4 --ghost $g --frames $seamFrames \
      --image "$work/dp-seam-$g.pfm"
  done
  # The two scenes' images (the README's and the plot's reference), 2 threads, one rank.
  mpi 1 "$dfbwall" --renderer scivis --quiet --scene "$skew" --size $memsize --image "$work/dp-skew.png"
  mpi 1 "$dfbwall" --renderer scivis --quiet --scene "$wave" --size $memsize --image "$work/dp-wavelet.png"

  # ---- Strong scaling. ----
  local scaleRows="" scaleDat="$work/dp-scale.dat" base4="" base0="" med mad cnt f
  : >"$scaleDat"
  for n in "${counts[@]}"; do
    local line="$n"
    for b in 4 0; do
      read -r med mad cnt < <(for f in "$work"/dp-scale-b$b-n$n-*.json; do dp_frames "$f"; done | awk '{print $1}' | medmad)
      [ $b = 4 ] && [ -z "$base4" ] && base4=$med
      [ $b = 0 ] && [ -z "$base0" ] && base0=$med
      local sp sp4
      if [ $b = 4 ]; then sp=$(awk -v a="$base4" -v m="$med" 'BEGIN {printf "%.3g", a / m}')
      else sp=$(awk -v a="$base0" -v m="$med" 'BEGIN {printf "%.3g", a / m}'); fi
      sp4=$(awk -v a="$base4" -v m="$med" 'BEGIN {printf "%.3g", a / m}')
      scaleRows+="${scaleRows:+,}
    {\"ranks\": $n, \"bricks\": $b, \"oversubscribed\": $([ "$n" -gt "$(nproc)" ] && echo true || echo false), \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"speedup_vs_1_rank_same_mode\": $sp, \"speedup_vs_1_rank_4_bricks\": $sp4}"
      echo "  $n rank(s), --bricks $b: median $med ms (MAD $mad, $cnt frames), speed-up ${sp}x vs 1 rank (${sp4}x vs 1 rank with 4 bricks)"
      line+=" $med $mad $sp"
    done
    echo "$line" >>"$scaleDat"
  done

  # ---- Compositing overhead share, 2 and 4 ranks, 4 bricks. ----
  local compRows="" compDat="$work/dp-comp.dat" compGoal=met
  : >"$compDat"
  for n in 2 4; do
    for f in "$work"/dp-scale-b4-n$n-*.json; do dp_frames "$f"; done |
      awk -v n="$n" '{print n, 100 * $3 / $1, 100 * ($1 - $2) / $1}' | tee "$work/dp-comp-$n.dat" >>"$compDat"
    local sm smad sc bm bmad
    read -r sm smad sc < <(awk -v n="$n" '$1 == n {print $2}' "$compDat" | medmad)
    read -r bm bmad _ < <(awk -v n="$n" '$1 == n {print $3}' "$compDat" | medmad)
    awk -v m="$sm" 'BEGIN {exit !(m > 10)}' && compGoal=missed
    compRows+="${compRows:+,}
    {\"ranks\": $n, \"composite_share_percent\": {\"median\": $sm, \"mad\": $smad}, \"not_rendering_share_percent\": {\"median\": $bm, \"mad\": $bmad}, \"frames\": $sc}"
    echo "  $n ranks: composite_ms / frame_ms median ${sm}% (MAD $smad); (frame_ms - render_ms) / frame_ms median ${bm}% (MAD $bmad)"
  done

  # ---- Memory. ----
  local memRows="" memDat="$work/dp-mem.dat" whole wholeNoAo memGoal=missed memGoalReach=missed
  : >"$memDat"; : >"$work/dp-mem-on.dat"; : >"$work/dp-mem-off.dat"
  whole=$(dp_ranks "$work/dp-mem-on-b1-n1.json" scene_bytes | head -1)
  wholeNoAo=$(dp_ranks "$work/dp-mem-off-b1-n1.json" scene_bytes | head -1)
  for ao in on off; do
    for n in "${counts[@]}"; do
      local ref=$whole row="" dat="$ao $n" sb1 rss1
      [ $ao = on ] || ref=$wholeNoAo
      for g in reach layer; do
        local f="$work/dp-mem-$ao-b4$g-n$n.json" sb4 rss4 max4 share
        sb4=$(dp_ranks "$f" scene_bytes | dp_json_list)
        rss4=$(dp_ranks "$f" peak_rss_kib | dp_json_list)
        max4=$(dp_ranks "$f" scene_bytes | sort -g | tail -1)
        share=$(awk -v a="$max4" -v b="$ref" 'BEGIN {printf "%.3g", 100 * a / b}')
        if [ $ao = on ] && [ "$n" = 4 ] && awk -v s="$share" 'BEGIN {exit !(s <= 30)}'; then
          [ $g = layer ] && memGoal=met || memGoalReach=met
        fi
        row+=" \"bricks_4_ghost_$g\": {\"scene_bytes\": $sb4, \"peak_rss_kib\": $rss4, \"max_scene_bytes_percent_of_whole\": $share},"
        echo "  AO $ao, $n rank(s), --bricks 4 --ghost $g: scene_bytes/rank $sb4 (max ${share}% of the whole scene), peak RSS KiB $rss4"
        dat+=" $max4 $(dp_ranks "$f" peak_rss_kib | sort -g | tail -1) $share"
      done
      sb1=$(dp_ranks "$work/dp-mem-$ao-b1-n$n.json" scene_bytes | dp_json_list)
      rss1=$(dp_ranks "$work/dp-mem-$ao-b1-n$n.json" peak_rss_kib | dp_json_list)
      echo "  AO $ao, $n rank(s), whole scene on every rank: scene_bytes $sb1, peak RSS KiB $rss1"
      memRows+="${memRows:+,}
    {\"ao\": \"$ao\", \"ranks\": $n,$row
     \"whole_scene_every_rank\": {\"scene_bytes\": $sb1, \"peak_rss_kib\": $rss1}}"
      # ao ranks | reach: max scene_bytes, max RSS, share | layer: the same | whole: bytes, RSS
      echo "$dat $(dp_ranks "$work/dp-mem-$ao-b1-n$n.json" scene_bytes | sort -g | tail -1) $(dp_ranks "$work/dp-mem-$ao-b1-n$n.json" peak_rss_kib | sort -g | tail -1)" |
        tee -a "$work/dp-mem-$ao.dat" >>"$memDat"
    done
  done
  # AO seams: largest per-channel difference against the unbricked render, and how many
  # channels differ by more than 1e-4.
  local seams
  seams=$("$root/scripts/pfm-diff" "$work/dp-seam-whole.pfm" "$work/dp-seam-reach.pfm" "$work/dp-seam-layer.pfm" |
    awk '{name = (NR == 1 ? "reach" : "layer")
          printf "%s\"%s\": {\"max_abs_difference\": %s, \"channels_over_1e-4\": %s, \"channels\": %s}", (NR > 1 ? ", " : ""), name, $2, $3, $4}')
  echo "  AO seams, 4 bricks vs the unbricked render ($memsize, $seamFrames frames, shadows off): {$seams}"

  # ---- Skewed scene: replication 2 vs 1. ----
  local skewRows="" skewDat="$work/dp-skew.dat" m1 m2 ratio skewGoal
  : >"$skewDat"
  for k in 1 2; do
    read -r med mad cnt < <(for f in "$work"/dp-skew-k$k-*.json; do dp_frames "$f"; done | awk '{print $1}' | medmad)
    # Per rank: render ms summed over the runs' frames and the brick tiles it rendered.
    local rend tiles
    rend=$(for r in 1 2 3 4; do for f in "$work"/dp-skew-k$k-*.json; do dp_ranks "$f" render | sed -n "${r}p"; done | awk '{s += $1} END {printf "%.0f\n", s}'; done | dp_json_list)
    tiles=$(for r in 1 2 3 4; do for f in "$work"/dp-skew-k$k-*.json; do dp_ranks "$f" brick_tiles_rendered | sed -n "${r}p"; done | awk '{s += $1} END {printf "%.0f\n", s}'; done | dp_json_list)
    skewRows+="${skewRows:+,}
    {\"replication\": $k, \"median_frame_ms\": $med, \"mad_frame_ms\": $mad, \"frames\": $cnt, \"render_ms_per_rank\": $rend, \"brick_tiles_per_rank\": $tiles}"
    echo "  skewed, 4 ranks, --replication $k: median $med ms (MAD $mad); render ms per rank $rend; brick tiles $tiles"
    echo "K=$k $med $mad" >>"$skewDat"
    eval "m$k=$med"
  done
  ratio=$(awk -v a="$m1" -v b="$m2" 'BEGIN {printf "%.3g", a / b}')
  skewGoal=$(awk -v r="$ratio" 'BEGIN {print (r >= 1.3) ? "met" : "missed"}')
  # How skewed: brick 0's rank's share of all render time with replication 1.
  local skewShare
  skewShare=$(for f in "$work"/dp-skew-k1-*.json; do dp_ranks "$f" render | awk '{s += $1; if (NR == 1) z = $1} END {print z, s}'; done |
    awk '{z += $1; s += $2} END {printf "%.3g", 100 * z / s}')
  echo "  skewed: replication 2 is ${ratio}x faster than replication 1 (goal >= 1.3x: $skewGoal); brick 0's rank did ${skewShare}% of the render time with replication 1"
  echo "  compositing share goal (<= 10% median): $compGoal; memory goal (4 bricks on 4 ranks, AO on, <= 30% of the whole scene): --ghost layer $memGoal, --ghost reach $memGoalReach"

  local load1
  load1=$(cut -d' ' -f1-3 /proc/loadavg)
  cat >"$results/dataparallel.json" <<EOF
{"figure": "dataparallel", "machine": $machine,
 "setup": {"renderer": "scivis", "threads_per_rank": 1, "size": "$size", "frames_per_run": $frames, "runs": $reps, "orbit_degrees_per_frame": $step,
           "oversubscription": "$(nproc) cores: 1 and 2 ranks have a core each, 4 ranks share 2 cores (2x oversubscribed)",
           "load_average_before": "$load0", "load_average_after": "$load1",
           "scaling_scene": "wavelet ${res}^3 (faint cool-warm volume, isosurfaces 160 and 215), AO 1 ray up to 0.3 (domain 2), camera of builtin:wavelet",
           "skewed_scene": "1e6 translucent particles (opacity 0.35, radius 0.006, 2 AO rays up to 0.1) clumped inside brick 0 (x<0, y<0); invisible 32^3 volume spans [-1,1]^3",
           "composite_share": "composite_ms / frame_ms as in --stats (from the slowest rank's last setTile to the frame complete on all ranks: the paper's compositing overhead); not_rendering_share = (frame_ms - render_ms) / frame_ms, an upper bound of the compositing tail after the slowest rank's last tile"},
 "strong_scaling": [$scaleRows
 ],
 "compositing": {"target": "median composite_ms / frame_ms <= 10% on 2 and 4 ranks: $compGoal", "results": [$compRows
 ]},
 "memory": {"whole_scene_bytes": {"ao_on": $whole, "ao_off": $wholeNoAo},
            "target": "with 4 bricks on 4 ranks each rank's scene_bytes <= 30% of the whole scene (AO on): --ghost layer $memGoal, --ghost reach $memGoalReach",
            "ao_seams_vs_unbricked": {"setup": "$memsize, $seamFrames frames accumulated, shadows off, linear radiance per channel", $seams},
            "results": [$memRows
 ]},
 "skewed": {"replication_2_over_1": $ratio, "brick0_rank_share_of_render_ms_replication_1_percent": $skewShare,
            "target": "replication 2 >= 1.3x faster than replication 1: $skewGoal", "results": [$skewRows
 ]}}
EOF

  local gp="$work/dp.gp"
  cat >"$gp" <<EOF
set multiplot layout 2,2 title "dfbwall scivis data-parallel (--bricks), 1 thread/rank, $(nproc) cores: 4 ranks oversubscribed; $size, median +- MAD"
set style fill solid 0.6; set key top right font ",9"
set title "Strong scaling, ${res}^3 wavelet"; set ylabel "ms per frame"; set yrange [0:*]
set style data histogram; set style histogram errorbars gap 1 lw 1
plot '$scaleDat' using 2:3:xtic(sprintf("%d rank(s)", \$1)) title "--bricks 4 (data-parallel)" lc rgb "#3070b0", \
     '' using 5:6 title "--bricks 0 (image-parallel)" lc rgb "#c08030", \
     '' using (\$0 - 0.17):2:(sprintf("%.2fx", \$4)) with labels offset 0,1 font ",8" notitle, \
     '' using (\$0 + 0.17):5:(sprintf("%.2fx", \$7)) with labels offset 0,1 font ",8" notitle
set style data linespoints
set title "Compositing overhead per frame, --bricks 4"; set ylabel "% of frame time"; set xlabel "frame (pooled runs)"
set yrange [0:100]
plot '$work/dp-comp-2.dat' using 0:2 pt 7 lc rgb "#3070b0" title "2 ranks: composite_ms / frame_ms", \
     '$work/dp-comp-4.dat' using 0:2 pt 5 lc rgb "#c03030" title "4 ranks: composite_ms / frame_ms", \
     '$work/dp-comp-2.dat' using 0:3 pt 6 dt 2 lc rgb "#3070b0" title "2 ranks: (frame - render) / frame", \
     '$work/dp-comp-4.dat' using 0:3 pt 4 dt 2 lc rgb "#c03030" title "4 ranks: (frame - render) / frame", \
     10 with lines dt 3 lc rgb "black" title "goal 10%"
unset xlabel
set title "Memory per rank (max over ranks), ${res}^3 wavelet"; set ylabel "MiB"; set yrange [0:*]
set xrange [0.5:4.5]; set xtics (1, 2, 4); set xlabel "ranks"
plot '$work/dp-mem-on.dat' using 2:(\$3 / 1048576) pt 7 lc rgb "#3070b0" title "scene_bytes, 4 bricks, ghost reach, AO on", \
     '$work/dp-mem-on.dat' using 2:(\$6 / 1048576) pt 5 lc rgb "#60a0e0" title "scene_bytes, 4 bricks, ghost layer, AO on", \
     '$work/dp-mem-off.dat' using 2:(\$3 / 1048576) pt 6 dt 2 lc rgb "#3070b0" title "scene_bytes, 4 bricks, AO off (both modes)", \
     '$work/dp-mem-on.dat' using 2:(\$9 / 1048576) pt 13 lc rgb "#c08030" title "scene_bytes, whole scene", \
     '$work/dp-mem-on.dat' using 2:(\$4 / 1024) pt 9 lc rgb "#30a030" title "peak RSS, 4 bricks, ghost reach", \
     '$work/dp-mem-on.dat' using 2:(\$7 / 1024) pt 8 lc rgb "#80d080" title "peak RSS, 4 bricks, ghost layer", \
     '$work/dp-mem-on.dat' using 2:(\$10 / 1024) pt 11 lc rgb "#c03030" title "peak RSS, whole scene"
unset xlabel; set xrange [*:*]; set xtics autofreq
set title "Skewed, 4 ranks, 4 bricks (brick 0: ${skewShare}% of render): K=1/K=2 = ${ratio}x"
set ylabel "ms per frame"; set yrange [0:*]
set style data histogram; set style histogram errorbars gap 1 lw 1
plot '$skewDat' using 2:3:xtic(1) title "--replication K" lc rgb "#3070b0"
unset multiplot
EOF
  gnuplot -e "set terminal pngcairo size 1300,950 noenhanced; set output '$results/dataparallel.png'" "$gp"
  cat >"$work/dp-images.gp" <<EOF
set multiplot layout 1,2
unset border; unset tics; unset key; set size ratio -1
set title "${res}^3 wavelet (scaling, memory)"
plot '$work/dp-wavelet.png' binary filetype=png with rgbimage
set title "skewed: particle cluster in brick 0"
plot '$work/dp-skew.png' binary filetype=png with rgbimage
unset multiplot
EOF
  gnuplot -e "set terminal pngcairo size 900,420 noenhanced; set output '$results/dataparallel-scenes.png'" "$work/dp-images.gp"
}
