# Figure "paraview" of scripts/bench (sourced by it; uses its helpers and variables): dfbwall's
# data-parallel scivis path beside ParaView 5.11 (Debian's `paraview`, pvbatch under MPI,
# offscreen under Xvfb, IceT compositing) on the same data, ranks and image size.
#  - Scenes: configs/scenes/wavelet256-volume.toml (the 256^3 wavelet as a volume: colour and
#    opacity map of `scripts/bench scivis`, one sample per voxel) and wavelet256-contours.toml
#    (two opaque isosurfaces of it; PARAVIEW_SCENES="contours" runs one). pvbatch reads the same files (bench/paraview_wavelet.py):
#    ParaView's Wavelet source at the extent [0, 255]^3 (the same field voxel for voxel), the
#    volume representation or one Contour filter per value, the same camera turned the same way.
#  - dfbwall --renderer scivis --bricks N on N ranks vs pvbatch on N ranks (N = 1, 2, 4), at
#    512^2, 1024^2 and 2048^2 (--quick: 512^2 only), orbit of FRAMES frames; each point runs dfbwall then
#    ParaView (interleaved), seconds per frame as median and MAD with the first frame left out.
#  - Threads: ceil(cores / N) per rank for both (dfbwall --threads, llvmpipe's LP_NUM_THREADS),
#    so 4 ranks on 2 cores are 2x oversubscribed for both.
#  - ParaView's volume mapper: "GPU Based" (vtkOpenGLGPUVolumeRayCastMapper, here on Mesa's
#    llvmpipe, so on the CPU too), the faster of ParaView's two here; PARAVIEW_MAPPER="Ray Cast
#    Only" picks the fixed-point CPU caster (which ignores LP_NUM_THREADS and takes every core).
# Not compared: ParaView's tiled display (pvserver --tdx 2 --tdy 2 + a pvpython client) against
# the 2x2 wall. Tried here (4 pvserver ranks, each tile window on its own Xvfb through
# --displays, --force-onscreen-rendering; the client connected and rendered the contour of 1.6 M
# triangles): the four "ParaView Server #k" windows exist (960x540 each), but xwd captures of
# every tile's display stayed black during and after the client's renders, while the client's
# screenshot held the whole image. What each tile shows cannot be checked, and a frame time
# would time the client's image, not the wall's (see README, "ParaView").
# ParaView is installed here, never by scripts/setup: `paraview` from Debian (about 1.2 GB, a few
# minutes) without its recommended python3-paraview, which conflicts with python3-vtk9 (the
# scivis figure's VTK): python3-paraview is unpacked with dpkg -x into $build/paraview-python
# and put on PYTHONPATH for pvbatch only, so both figures run on one machine.

pv_setup() {
  command -v Xvfb >/dev/null || { echo "bench: Xvfb missing (package xvfb)" >&2; return 1; }
  if ! command -v pvbatch >/dev/null; then
    echo "bench: installing paraview (Debian, about 1.2 GB; not a project dependency)"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq -o DPkg::Lock::Timeout=600 \
      --no-install-recommends paraview >/dev/null
  fi
  pvpath=""
  if ! dpkg-query -W -f '${Status}' python3-paraview 2>/dev/null | grep -q "ok installed"; then
    local unpacked="$build/paraview-python" version
    version=$(dpkg-query -W -f '${Version}' paraview)
    if [ "$(cat "$unpacked/version" 2>/dev/null)" != "$version" ]; then
      rm -rf "$unpacked" && mkdir -p "$unpacked/deb"
      (cd "$unpacked/deb" && apt-get download "python3-paraview=$version" >/dev/null 2>&1) ||
        { echo "bench: cannot download python3-paraview $version" >&2; return 1; }
      dpkg -x "$unpacked"/deb/python3-paraview_*.deb "$unpacked"
      rm -rf "$unpacked/deb"
      echo "$version" >"$unpacked/version"
    fi
    pvpath="$unpacked/usr/lib/python3/dist-packages"
  fi
}

# pv_xvfb_start / pv_xvfb_stop: one Xvfb for every pvbatch run of the figure. Not `xvfb-run -a`,
# which races with other Xvfb servers started at the same moment, and not a display below 10:
# hwloc (in every mpirun/orted on the machine) opens a connection to each of :0 ... :9 to look
# for GPUs, so a busy machine keeps such a server busy with strangers.
pv_xvfb_start() {
  local d
  for d in $(seq 150 199); do
    [ ! -e "/tmp/.X$d-lock" ] && [ ! -e "/tmp/.X11-unix/X$d" ] || continue
    Xvfb ":$d" -screen 0 1920x1080x24 -nolisten tcp >/dev/null 2>&1 &
    pv_xvfb_pid=$!
    trap pv_xvfb_stop EXIT  # also when a run fails and set -e ends scripts/bench
    local i
    for i in $(seq 50); do
      [ -e "/tmp/.X11-unix/X$d" ] && { pv_display=$d; return 0; }
      kill -0 "$pv_xvfb_pid" 2>/dev/null || break
      sleep 0.2
    done
    pv_xvfb_stop
  done
  echo "bench: could not start Xvfb on any of :150 ... :199" >&2
  return 1
}
pv_xvfb_stop() {
  [ -z "${pv_xvfb_pid:-}" ] || { kill "$pv_xvfb_pid" 2>/dev/null; wait "$pv_xvfb_pid" 2>/dev/null || true; }
  pv_xvfb_pid=""
  trap - EXIT
}

# pv_run N THREADS ERRFILE ARGS...: pvbatch on N ranks under the figure's Xvfb; its JSON line on
# stdout. Seen here on a busy machine: a rank's XOpenDisplay now and then fails with the server
# up and answering. In the window set-up that rank aborts ("bad X server connection"); in
# ParaView's rendering-capabilities check it only makes ParaView think a rank cannot render, and
# ParaView then quietly delivers all data to rank 0 and renders it there ("require remote
# rendering which, however, is not available"): not data-parallel, so not this comparison.
# Either run is started again, four times at most.
pv_run() {
  local n=$1 threads=$2 err=$3 attempt
  shift 3
  for attempt in 1 2 3 4 5; do
    local rc=0
    env DISPLAY=":$pv_display" HWLOC_COMPONENTS=-gl ${pvpath:+PYTHONPATH=$pvpath} timeout -k 5 240 \
      mpiexec -n "$n" --oversubscribe --bind-to none -x DISPLAY -x LP_NUM_THREADS="$threads" \
      ${pvpath:+-x PYTHONPATH} pvbatch --force-offscreen-rendering "$root/bench/paraview_wavelet.py" \
      "$@" 2>"$err" >"$err.out" || rc=$?
    if [ $rc -eq 0 ] && ! grep -q "remote rendering which, however, is not available" "$err"; then
      grep '^{' "$err.out"
      return 0
    fi
    # Seen here too: after one rank lost the display the others spun in a collective for good.
    if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
      echo "  (pvbatch did not finish in 4 minutes, attempt $attempt; again)" >&2
      continue
    fi
    grep -q "bad X server connection\|remote rendering which, however, is not available" "$err" || return 1
    echo "  (a pvbatch rank could not open the X display, attempt $attempt; again)" >&2
  done
  return 1
}

# pv_frames FILE: the per-frame seconds of a pvbatch JSON line, frame 0 (set-up) left out.
pv_frames() { sed -n 's/.*"frame_s": *\[\([^]]*\)\].*/\1/p' "$1" | tr ',' '\n' | awk 'NR > 1 {print $1 + 0}'; }

# pfm_png IN.pfm OUT.png: dfbwall's linear image as 8-bit colours, clamped and not sRGB-encoded,
# as ParaView writes its screenshots (the PFM's rows run bottom to top, as gnuplot plots them).
pfm_png() {
  local w h skip
  read -r w h < <(sed -n 2p "$1")
  skip=$(head -3 "$1" | wc -c)
  cat >"$2.gp" <<EOF
set terminal pngcairo size $w,$h; set output '$2'
set lmargin 0; set rmargin 0; set tmargin 0; set bmargin 0; unset border; unset tics; unset key
set xrange [0:$((w - 1))]; set yrange [0:$((h - 1))]
clamp(v) = v < 0 ? 0 : (v > 1 ? 255 : 255 * v)
plot '$1' binary skip=$skip array=($w,$h) format='%float32%float32%float32' \\
  using (clamp(\$1)):(clamp(\$2)):(clamp(\$3)) with rgbimage
EOF
  gnuplot "$2.gp"
}

fig_paraview() {
  local frames=5 sizes=(512 1024 2048) counts=(1 2 4) reps=1
  [ $quick = 1 ] && frames=4 sizes=(512)
  local step=$((360 / 24)) mapper="${PARAVIEW_MAPPER:-GPU Based}" scenes
  read -r -a scenes <<<"${PARAVIEW_SCENES:-volume contours}"
  pv_setup || return 1
  pv_xvfb_start || return 1
  local load0
  load0=$(cut -d' ' -f1-3 /proc/loadavg)
  echo "== paraview: 256^3 wavelet, dfbwall --bricks N vs pvbatch ($mapper) on N ranks, ${sizes[*]}^2, $frames-frame orbit (load $load0)"
  local rep scene size n threads tag
  for rep in $(seq "$reps"); do
    for scene in "${scenes[@]}"; do
      for size in "${sizes[@]}"; do
        for n in "${counts[@]}"; do
          threads=$((($(nproc) + n - 1) / n))
          tag="$scene-$size-n$n-$rep"
          # dfbwall first, then ParaView: the pair sees the same moment of the machine.
          mpi "$n" "$dfbwall" --renderer scivis --scene "$root/configs/scenes/wavelet256-$scene.toml" \
            --size "${size}x$size" --bricks "$n" --threads "$threads" --spp 1 --orbit $step \
            --frames "$frames" --quiet --stats "$work/pv-dfb-$tag.json" --image "$work/pv-dfb-$scene-$size-n$n.pfm"
          pv_run "$n" "$threads" "$work/pv-pv-$tag.err" "$root/configs/scenes/wavelet256-$scene.toml" "$size" \
            "$frames" $step "$mapper" "$work/pv-pv-$scene-$size-n$n.png" >"$work/pv-pv-$tag.json" ||
            { echo "bench: pvbatch failed ($work/pv-pv-$tag.err):" >&2; grep -m3 ERR "$work/pv-pv-$tag.err" >&2; pv_xvfb_stop; return 1; }
          echo "  $scene ${size}^2, $n rank(s) x $threads thread(s): done (load $(cut -d' ' -f1 /proc/loadavg))"
        done
      done
    done
  done
  pv_xvfb_stop
  local load1
  load1=$(cut -d' ' -f1-3 /proc/loadavg)

  local rows="" dat="$work/pv.dat" goal=met ratios="" f
  : >"$dat"
  for scene in "${scenes[@]}"; do
    for size in "${sizes[@]}"; do
      for n in "${counts[@]}"; do
        local dm dmad dn pm pmad pn ratio tri
        read -r dm dmad dn < <(for f in "$work"/pv-dfb-$scene-$size-n$n-*.json; do frames_of "$f" frame_ms; done |
          awk '{print $1 / 1000}' | medmad)
        read -r pm pmad pn < <(for f in "$work"/pv-pv-$scene-$size-n$n-*.json; do pv_frames "$f"; done | medmad)
        ratio=$(awk -v a="$dm" -v b="$pm" 'BEGIN {printf "%.3g", b / a}')
        tri=$(grep -o '"triangles": *[0-9]*' "$work"/pv-pv-$scene-$size-n$n-1.json | sed 's/.*: *//')
        # Camera rays the bricks did not trace, hidden behind a nearer brick's opaque isosurface
        # (BrickOcclusion), over the run's frames and ranks.
        local skipped
        skipped=$({ grep -ho '"brick_rays_skipped": *[0-9.e+]*' "$work"/pv-dfb-$scene-$size-n$n-*.json || true; } |
          sed 's/.*: *//' | awk '{s += $1} END {printf "%.0f\n", s}')
        awk -v r="$ratio" 'BEGIN {exit !(r < 3)}' && goal=missed
        ratios+="$ratio "
        rows+="${rows:+,}
    {\"scene\": \"$scene\", \"size\": $size, \"ranks\": $n, \"threads_per_rank\": $((($(nproc) + n - 1) / n)),
     \"dfbwall_s\": {\"median\": $dm, \"mad\": $dmad, \"frames\": $dn}, \"paraview_s\": {\"median\": $pm, \"mad\": $pmad, \"frames\": $pn},
     \"paraview_over_dfbwall\": $ratio, \"paraview_triangles\": ${tri:-0}, \"dfbwall_rays_skipped\": ${skipped:-0}}"
        echo "  $scene ${size}^2 $n rank(s): dfbwall $dm s (MAD $dmad), ParaView $pm s (MAD $pmad) per frame: dfbwall ${ratio}x ParaView's frame rate"
        echo "$scene/${size}/${n}r $dm $dmad $pm $pmad $ratio" >>"$dat"
      done
    done
  done
  local medratio
  medratio=$(tr ' ' '\n' <<<"$ratios" | grep . | median)
  echo "  goal dfbwall >= 3x ParaView's frame rate at every point: $goal (median ratio ${medratio}x; load $load0 before, $load1 after)"
  cat >"$results/paraview.json" <<EOF
{"figure": "paraview", "machine": $machine,
 "setup": {"paraview": "$(dpkg-query -W -f '${Version}' paraview) (Debian), pvbatch --force-offscreen-rendering under Xvfb and mpiexec, IceT compositing",
           "paraview_volume_mapper": "$mapper",
           "scenes": {"volume": "configs/scenes/wavelet256-volume.toml", "contours": "configs/scenes/wavelet256-contours.toml"},
           "data": "256^3 wavelet: ParaView's Wavelet source over [0,255]^3 centred in it = dfbwall's source = wavelet at dims 256; split over the ranks (dfbwall --bricks N, ParaView's pieces)",
           "frames_per_run": $frames, "runs": $reps, "orbit_degrees_per_frame": $step, "first_frame_left_out": true,
           "threads_per_rank": "ceil(cores / ranks): dfbwall --threads, ParaView LP_NUM_THREADS (llvmpipe); 4 ranks on $(nproc) cores are oversubscribed",
           "sampling": "volume: one sample per voxel spacing for both (dfbwall sampling_rate 1, VTK GPU caster's auto sample distance = the smallest spacing), trilinear, no shading; early termination dfbwall 1/128 transmittance, VTK's GPU caster at opacity 0.99",
           "differences": "contours: ParaView extracts 1.6 M triangles once (not timed) and rasterises them every frame with llvmpipe; dfbwall polygonises them once at load (marching cubes, not timed) and finds each pixel's first hit with Embree or, where a voxel cell spans at least 2.75 pixels, with its own raster of the triangles (FirstHitRaster: the same hits); lighting: ParaView's light kit vs dfbwall's ambient + headlight; dfbwall jitters volume samples per pixel; images: dfbwall's linear colours shown without sRGB encoding, as ParaView writes them",
           "load_average_before": "$load0", "load_average_after": "$load1"},
 "tiled_display": "not compared: pvserver --tdx 2 --tdy 2 (4 ranks, a tile window per rank on its own Xvfb via --displays, --force-onscreen-rendering) + a pvpython client starts and renders, but every tile window stayed black in xwd captures (the client's screenshot held the whole image), so neither tiling nor a wall frame time can be observed here",
 "goal": "dfbwall >= 3x ParaView's frame rate at every point: $goal",
 "median_ratio": $medratio,
 "points": [$rows
 ]}
EOF

  # The chart, then both renderers' images of the first size on the most ranks, side by side.
  local s0=${sizes[0]} nl=${counts[-1]} img
  for scene in "${scenes[@]}"; do
    pfm_png "$work/pv-dfb-$scene-$s0-n$nl.pfm" "$work/pv-dfb-$scene.png"
  done
  cat >"$work/pv.gp" <<EOF
set multiplot title "256^3 wavelet, dfbwall --bricks N vs ParaView 5.11 pvbatch on N ranks, $(nproc) cores (load $load0 .. $load1)" font ",12"
set origin 0, 0.45; set size 1, 0.5
set title "seconds per frame over the orbit (median +- MAD, log scale); labels: dfbwall's frame rate / ParaView's" font ",10"
set style data histogram; set style histogram errorbars gap 1 lw 1; set style fill solid 0.6
set ylabel "s per frame"; set logscale y; set key top left; set xtics rotate by -30 font ",9"
plot '$dat' using 2:3:xtic(1) title "dfbwall scivis" lc rgb "#3070b0", \
     '' using 4:5 title "ParaView ($mapper)" lc rgb "#c08030", \
     '' using (\$0):(\$4 * 1.6):(sprintf("%.1fx", \$6)) with labels font ",8" notitle
unset logscale y; unset border; unset tics; unset key; unset ylabel
set size ratio -1
EOF
  # Each scene that ran: dfbwall's image and ParaView's, side by side.
  local column=0
  for scene in "${scenes[@]}"; do
    cat >>"$work/pv.gp" <<EOF
set origin $(awk "BEGIN {print $column * 0.25}"), 0; set size 0.25, 0.42
set title "dfbwall, $scene (${s0}^2, $nl ranks)" font ",10"
plot '$work/pv-dfb-$scene.png' binary filetype=png with rgbimage
set origin $(awk "BEGIN {print ($column + 1) * 0.25}"), 0; set title "ParaView, $scene"
plot '$work/pv-pv-$scene-$s0-n$nl.png' binary filetype=png with rgbimage
EOF
    column=$((column + 2))
  done
  echo "unset multiplot" >>"$work/pv.gp"
  gnuplot -e "set terminal pngcairo size 1400,1000 noenhanced; set output '$results/paraview.png'" "$work/pv.gp"
}
