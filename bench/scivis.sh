# Figure "scivis" of scripts/bench (sourced by it; uses its helpers and variables).
# The scivis renderer on VTK's wavelet, beside VTK's CPU volume ray caster
# (vtkFixedPointVolumeRayCastMapper, python3-vtk9) on the same field, image size, camera,
# transfer function (blue-white-red over 37..277, opacity ramp 0..0.4 per voxel), one sample per
# voxel and early termination at 1/128 transmittance as VTK's caster stops. Runs interleave
# (ours, VTK, ours, VTK ...). Also ns per camera ray on two opaque isosurfaces (triangles made at
# load), alone and with 4 AO rays and shadows.
fig_scivis() {
  local frames=8 sizes=(512 1024) resolutions=(256 512)
  [ $quick = 1 ] && frames=4 sizes=(512) resolutions=(256)
  command -v xvfb-run >/dev/null || { echo "bench: xvfb-run missing" >&2; return 1; }
  /usr/bin/python3 -c "import vtk" 2>/dev/null || {
    $sudo apt-get install -y -qq --no-install-recommends python3-vtk9 >/dev/null; }
  cmake --build "$build" -j "$(nproc)" --target scivis_bench >/dev/null
  local bench="$build/bench/renderers/scivis_bench" vtkpy="$root/bench/renderers/vtk_volume.py"
  echo "== scivis: wavelet volume vs VTK's fixed-point ray caster, $frames-frame orbit"
  local rows="" dat="$work/scivis.dat"
  : >"$dat"
  for res in "${resolutions[@]}"; do
    for size in "${sizes[@]}"; do
      for threads in 1 2; do
        local ours vtk a b
        ours=$("$bench" volume "$res" "$size" "$threads" "$frames" "$work/scivis-ours-$res-$size.png")
        vtk=$(xvfb-run -a -s "-screen 0 1280x1024x24" /usr/bin/python3 "$vtkpy" "$res" "$size" \
          "$threads" "$frames" "$work/scivis-vtk-$res-$size.png")
        a=$(grep -o '"median_frame_s": [0-9.e+-]*' <<<"$ours" | awk '{print $2}')
        b=$(grep -o '"median_frame_s": [0-9.e+-]*' <<<"$vtk" | awk '{print $2}')
        ca=$(grep -o '"median_cpu_frame_s": [0-9.e+-]*' <<<"$ours" | awk '{print $2}')
        cb=$(grep -o '"median_cpu_frame_s": [0-9.e+-]*' <<<"$vtk" | awk '{print $2}')
        ns=$(grep -o '"ns_per_volume_sample": [0-9.e+-]*' <<<"$ours" | awk '{print $2}')
        echo "  ${res}^3 ${size}^2 ${threads} thread(s): dfbwall $a s, VTK $b s per frame," \
          "VTK/dfbwall $(awk -v a="$a" -v b="$b" 'BEGIN {printf "%.2f", b / a}')x" \
          "(CPU time $(awk -v a="$ca" -v b="$cb" 'BEGIN {printf "%.2f", b / a}')x), $ns ns per volume sample"
        echo "${res}^3/${size}^2/${threads}t $a $b $ns" >>"$dat"
        rows="$rows${rows:+,}
  {\"dfbwall\": $ours, \"vtk\": $vtk, \"speedup\": $(awk -v a="$a" -v b="$b" 'BEGIN {printf "%.3f", b / a}')}"
      done
    done
  done
  local iso="" line mode
  for mode in iso iso-ao; do
    for res in "${resolutions[@]}"; do
      for threads in 1 2; do
        line=$("$bench" "$mode" "$res" 512 "$threads" "$frames" "$work/scivis-$mode-$res.png")
        echo "  $mode ${res}^3 512^2 $threads thread(s): $(grep -o '"ns_per_camera_ray": [0-9.e+-]*' <<<"$line" | awk '{print $2}') ns per camera ray (per thread)"
        iso="$iso${iso:+,}
  $line"
      done
    done
  done
  local met nsMet
  met=$(awk '$3 / $2 < 2 {bad = 1} END {print bad ? "missed" : "met"}' "$dat")
  nsMet=$(awk '{n++; if ($4 <= 5) ok++} END {printf "met at %d of %d points", ok, n}' "$dat")
  echo "  goal dfbwall >= 2x VTK's frame rate at every point: $met; <= 5 ns per volume sample: $nsMet"
  cat >"$results/scivis.json" <<JSON
{"figure": "scivis", "machine": $machine,
 "setup": {"frames": $frames, "camera": "VTK ResetCamera view, orbit about the centre",
           "transfer_function": "37 (0.23,0.30,0.75) .. 157 (0.87,0.87,0.87) .. 277 (0.71,0.02,0.15); opacity 0 at 37 .. 0.4 at 277 per voxel",
           "sampling": "one sample per voxel spacing; early termination below 1/128 transmittance (VTK's threshold)"},
 "goal": "at least 2x VTK's frame rate: $met",
 "goal_ns_per_volume_sample": "at most 5 ns: $nsMet",
 "volume": [$rows
 ],
 "isosurfaces": [$iso
 ]}
JSON
  local chart="$work/scivis.gp" images="$work/scivis-images.gp"
  cat >"$chart" <<GP
set title "Wavelet volume, seconds per frame (lower is better)"
set ylabel "s per frame"; set yrange [0:*]; set key top left
set style data histogram; set style fill solid 0.6; set xtics rotate by -20
plot '$dat' using 2:xtic(1) title "dfbwall scivis" lc rgb "#3070b0", \
     '' using 3 title "VTK vtkFixedPointVolumeRayCastMapper" lc rgb "#c08030"
GP
  plot scivis "$chart"
  # Both images of the first configuration side by side.
  local r0=${resolutions[0]} s0=${sizes[0]}
  cat >"$images" <<GP
set multiplot layout 1,2
unset border; unset tics; unset key; set size ratio -1
set title "dfbwall scivis, ${r0}^3, ${s0}^2"
plot '$work/scivis-ours-$r0-$s0.png' binary filetype=png with rgbimage
set title "VTK fixed-point ray caster"
plot '$work/scivis-vtk-$r0-$s0.png' binary filetype=png with rgbimage
unset multiplot
GP
  gnuplot -e "set terminal pngcairo size $((2 * s0)),$((s0 + 40)) noenhanced; set output '$results/scivis-images.png'" "$images"
}
