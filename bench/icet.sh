# Figure "icet" of scripts/bench (sourced by it; uses its helpers and variables).
# The DFB against IceT (bench/icet/README.md) on the same bricks, one brick per rank, 1 thread
# per rank: VTK's wavelet (builtin:wavelet) blended in visibility order (transparent), and the
# same wavelet with both isosurfaces opaque and the volume hidden, z-composited (opaque);
# one image on rank 0 (tiles 1x1) and the display-wall case, a 2x2 tile layout shown by ranks
# 0-3 (IceT's tiles vs the DFB routing finished tiles to the display ranks, display format
# NONE, as dfbwall's route mode). icet_bench runs dfb, icet-reduce and icet-radixk interleaved
# frame by frame; bench/icet/figure.py takes the medians per point, writes icet.json and checks
# the goals. IceT is not a Debian package: it is built once from its source tarball
# (--icet-tarball=PATH or ICET_TARBALL, commit 088aa5a) into build-release/icet, beside the
# release build. Not in the default set. More ranks than the machine's cores are oversubscribed.
fig_icet() {
  local frames=3 sizes=(1024 2048) ranks=(2 4 8) modes=(transparent opaque)
  [ $quick = 1 ] && frames=2 sizes=(512) ranks=(2 4)
  [ -n "${ICET_TARBALL:-}" ] && [ -f "$ICET_TARBALL" ] || {
    echo "bench: icet needs IceT's source tarball: --icet-tarball=PATH or ICET_TARBALL=PATH" \
      "(bench/icet/README.md)" >&2
    return 1
  }
  local src="$build/icet-src" icet="$build/icet" stamp
  stamp=$(sha256sum "$ICET_TARBALL" | cut -d' ' -f1)
  if [ "$(cat "$icet/tarball.sha256" 2>/dev/null)" != "$stamp" ] || [ ! -f "$icet/lib/IceTConfig.cmake" ]; then
    echo "== icet: building IceT from $ICET_TARBALL in $icet"
    rm -rf "$src" "$icet"
    mkdir -p "$src"
    tar -xzf "$ICET_TARBALL" -C "$src" --strip-components=1
    # No OpenGL layers (IceT's GL3 test does not link on Debian 12) and no tests: core + MPI.
    cmake -S "$src" -B "$icet" -DCMAKE_BUILD_TYPE=Release -DICET_USE_OPENGL=OFF \
      -DICET_USE_OPENGL3=OFF -DICET_USE_MPI=ON -DICET_BUILD_TESTING=OFF -DBUILD_TESTING=OFF >/dev/null
    cmake --build "$icet" -j "$(nproc)" >/dev/null
    echo "$stamp" >"$icet/tarball.sha256"
  fi
  cmake -S "$root" -B "$build" -DDFBWALL_ICET_DIR="$icet/lib" >/dev/null
  cmake --build "$build" -j "$(nproc)" --target icet_bench >/dev/null
  local bench="$build/bench/icet/icet_bench" runs=() load_before load_after
  load_before=$(cut -d' ' -f1-3 /proc/loadavg)
  echo "== icet: DFB vs IceT on the same bricks, one per rank, $frames frames (+1 warm-up)," \
    "load $load_before"
  # One job per point; the variants interleave inside it. Tiled points need 4 display ranks.
  for size in "${sizes[@]}"; do
    for mode in "${modes[@]}"; do
      for n in "${ranks[@]}"; do
        for tiles in 1x1 2x2; do
          [ "$tiles" = 2x2 ] && [ "$n" -lt 4 ] && continue
          local name="icet-$mode-$size-$n-$tiles"
          mkdir -p "$work/$name"
          mpi "$n" "$bench" --scene builtin:wavelet --mode "$mode" --size "${size}x${size}" \
            --tiles "$tiles" --frames "$frames" --images "$work/$name" >"$work/$name.jsonl" \
            2>"$work/$name.err" || { cat "$work/$name.err" >&2; return 1; }
          runs+=("$work/$name.jsonl")
          echo "  $mode ${size}x$size, $n ranks, tiles $tiles: done (load $(cut -d' ' -f1 /proc/loadavg))"
        done
      done
    done
  done
  load_after=$(cut -d' ' -f1-3 /proc/loadavg)
  /usr/bin/python3 "$root/bench/icet/figure.py" --machine "$machine" \
    --load "$load_before -> $load_after" --json "$results/icet.json" --dat "$work/icet.dat" \
    "${runs[@]}"
  plot icet <(cat <<EOF
set terminal pngcairo size 1100,800 noenhanced; set output '$results/icet.png'
set multiplot layout 2,1 title "DFB vs IceT, same bricks (builtin:wavelet, 1 brick + 1 thread per rank; 2 cores: 4 and 8 ranks oversubscribed)"
set style data histogram; set style histogram clustered gap 1; set style fill solid 0.6
set xtics rotate by -35 font ",8"; set key outside top right; set grid ytics
set ylabel "total frame ms (median)"; set yrange [0:*]
plot '$work/icet.dat' using 2:xtic(1) title "DFB" lc rgb "#3070b0", \
     '' using 3 title "IceT reduce (default)" lc rgb "#c08030", \
     '' using 4 title "IceT radix-k" lc rgb "#60a050"
set ylabel "compositing overhead ms (median, log)"; set logscale y; set yrange [*:*]
plot '$work/icet.dat' using 5:xtic(1) title "DFB" lc rgb "#3070b0", \
     '' using 6 title "IceT reduce (default)" lc rgb "#c08030", \
     '' using 7 title "IceT radix-k" lc rgb "#60a050"
unset multiplot
EOF
)
}
