# Figure "icet" of scripts/bench (sourced by it; uses its helpers and variables).
# The DFB against IceT (bench/icet/README.md) on the same bricks, one brick per rank: VTK's
# wavelet volume blended in visibility order (transparent), and the many-spheres scene
# z-composited (opaque; z-compositing drops what lies behind, so it needs opaque fragments): icet_bench runs dfb, icet-reduce and icet-radixk interleaved frame by frame and prints
# one JSON line per frame and variant; here the medians of total and compositing overhead per
# point, and the largest image difference from the DFB's. IceT is not a Debian package: it is
# built from the tarball ICET_TARBALL names (IceT commit 088aa5a, e.g. GitLab's source archive
# of https://gitlab.kitware.com/paraview/icet) into the work folder. Not in the default set.
fig_icet() {
  local frames=6 sizes=(512 1024) ranks=(2 4) modes=(transparent opaque)
  [ $quick = 1 ] && frames=3 sizes=(512) modes=(transparent)
  [ -n "${ICET_TARBALL:-}" ] && [ -f "$ICET_TARBALL" ] || {
    echo "bench: icet needs ICET_TARBALL=<IceT source tarball> (bench/icet/README.md)" >&2
    return 1
  }
  local src="$work/icet-src" icet="$work/icet-build" ibuild="$root/build-icet"
  mkdir -p "$src"
  tar -xf "$ICET_TARBALL" -C "$src" --strip-components=1
  cmake -S "$src" -B "$icet" -DCMAKE_BUILD_TYPE=Release -DICET_USE_OPENGL=OFF -DICET_USE_MPI=ON \
    -DICET_BUILD_TESTING=OFF -DBUILD_TESTING=OFF >/dev/null
  cmake --build "$icet" -j "$(nproc)" >/dev/null
  cmake -S "$root" -B "$ibuild" -DCMAKE_BUILD_TYPE=Release -DDFBWALL_BUILD_TESTS=OFF \
    -DDFBWALL_ICET_DIR="$icet/lib" >/dev/null
  cmake --build "$ibuild" -j "$(nproc)" --target icet_bench >/dev/null
  local bench="$ibuild/bench/icet/icet_bench" points=""
  echo "== icet: DFB vs IceT on the same bricks, one per rank, $frames frames"
  for mode in "${modes[@]}"; do
    for size in "${sizes[@]}"; do
      for n in "${ranks[@]}"; do
        local out="$work/icet-$mode-$size-$n.jsonl" images="$work/icet-$mode-$size-$n"
        mkdir -p "$images"
        local scene=builtin:wavelet
        [ "$mode" = opaque ] && scene=builtin:spheres
        mpi "$n" "$bench" --scene "$scene" --mode "$mode" --size "${size}x${size}" \
          --frames "$frames" --images "$images" >"$out" 2>/dev/null
        local point
        point=$(/usr/bin/python3 - "$out" "$scene" <<'PY'
import json, statistics, sys
lines = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
frames = [l for l in lines if "variant" in l and not l["warmup"]]
checks = {l["image_check"]["variant"]: l["image_check"] for l in lines if "image_check" in l}
first = frames[0]
point = {"scene": sys.argv[2], "ranks": first["ranks"], "size": f'{first["width"]}x{first["height"]}',
         "mode": first["mode"], "frames": len(frames) // 3, "variants": {}}
for v in ("dfb", "icet-reduce", "icet-radixk"):
    mine = [l for l in frames if l["variant"] == v]
    point["variants"][v] = {
        "median_total_ms": statistics.median(l["total_ms"] for l in mine),
        "median_render_ms": statistics.median(l["render_ms"] for l in mine),
        "median_overhead_ms": statistics.median(l["overhead_ms"] for l in mine)}
    if v in checks:
        point["variants"][v]["image_max_abs_diff"] = checks[v]["max_abs_diff"]
        point["variants"][v]["image_diff_units"] = checks[v]["units"]
print(json.dumps(point))
PY
)
        echo "  $point"
        points="$points${points:+,}
  $point"
      done
    done
  done
  cat >"$results/icet.json" <<JSON
{"figure": "icet", "machine": $machine,
 "setup": {"scenes": "transparent: builtin:wavelet, opaque: builtin:spheres (gradient backgrounds replaced by their middle colour)",
           "bricks": "one per rank", "icet": "commit 088aa5a, REDUCE strategy, reduce = default single-image strategy",
           "overhead": "slowest rank's last local render -> finished image on rank 0 (paper 6.2.1)"},
 "points": [$points
 ]}
JSON
}
