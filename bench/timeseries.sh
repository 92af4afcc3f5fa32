# Figure "timeseries" of scripts/bench (sourced by it; uses its helpers and variables): a volume
# time series played one step a frame (fps = 0) with --bricks 4 on 3 render ranks, image only,
# per step the slowest rank's read (voxels from the files), build (macrocells, value ranges,
# isosurfaces and BVHs), the frame's wait for the prefetched step, the switch (the bricks'
# exchange, renderers) and the frame time, from --stats (docs/scivis.md, "Time series").
#   small: 64^3 steps at 800x600: reading keeps up, so frames should not wait;
#   large: 192^3 steps (more voxels, same reader) at 320x240: reading is slower than a
#          frame, so frames wait; the claim is that they wait no longer than the read and
#          build of the step itself (the prefetch overlaps the rest with the frame before).
# The steps are written by scripts/write_series.py (raw float32 NRRD) and read from the page
# cache. About 2 minutes; --quick about 40 s.
fig_timeseries() {
  local steps=50 big=192
  [ $quick = 1 ] && steps=16 big=128
  echo "== timeseries: $steps steps, --bricks 4 on 3 ranks, one step a frame"
  local out="$work/timeseries"
  mkdir -p "$out"
  local name dims size
  for variant in "small 64 800x600" "large $big 320x240"; do
    read -r name dims size <<<"$variant"
    mkdir -p "$out/$name"
    /usr/bin/python3 "$root/scripts/write_series.py" "$out/$name" "$steps" "$dims" "$dims" "$dims"
    cat >"$out/$name/series.toml" <<TOML
[camera]
position = [2.2, 1.4, 2.6]
look_at = [0, 0, 0]
fov = 40

[materials.skin]
type = "diffuse"
color = [0.9, 0.7, 0.4]

[[volumes]]
name = "blob"
source = "file"
spacing = $(awk -v n="$dims" 'BEGIN {print 2 / (n - 1)}')
origin = [-1, -1, -1]
file = "step-%02d.nrrd"
time_steps = $steps
transfer_function = { preset = "viridis", range = [0.0, 160.0], opacity = [[0, 0], [60, 0.02], [160, 0.3]] }

[[isosurfaces]]
volume = "blob"
value = 70.0
material = "skin"
TOML
    mpi 3 "$dfbwall" --renderer scivis --scene "$out/$name/series.toml" --bricks 4 \
      --size "$size" --frames "$steps" --spp 1 --quiet --stats "$out/$name.json" --timeout 120
  done
  /usr/bin/python3 - "$out" "$results/timeseries.json" "$machine" "$steps" "$big" <<'PY'
import json, statistics, sys
out, target, machine, steps, big = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
figure = {"figure": "timeseries", "machine": machine, "steps": steps, "variants": []}
def med(xs): return statistics.median(xs) if xs else 0.0
for name, dims, size in (("small", 64, "800x600"), ("large", big, "320x240")):
    frames = [json.loads(l) for l in open("%s/%s.json" % (out, name)) if l.startswith('{"frame"')]
    switched = [f for f in frames if "step" in f]
    per_step = [{"time_step": f["time_step"], "frame_ms": f["frame_ms"], **f["step"]} for f in switched]
    read = [s["read_ms"] for s in per_step]
    build = [s["build_ms"] for s in per_step]
    wait = [s["wait_ms"] for s in per_step]
    switch = [s["switch_ms"] for s in per_step]
    frame = [s["frame_ms"] for s in per_step]
    # A frame waits for its step at most for what reading and building it took.
    over = [s for s in per_step if s["wait_ms"] > s["read_ms"] + s["build_ms"] + 1.0]
    v = {"variant": name, "voxels": [dims] * 3, "size": size, "steps_switched": len(per_step),
         "read_ms": med(read), "build_ms": med(build), "wait_ms": med(wait),
         "wait_ms_max": max(wait) if wait else 0.0, "switch_ms": med(switch), "frame_ms": med(frame),
         "frames_waiting_over_1ms": sum(1 for w in wait if w > 1.0),
         "frames_waiting_longer_than_read_and_build": len(over), "per_step": per_step}
    figure["variants"].append(v)
    print("  %-5s %3d^3 at %s: median read %.1f ms, build %.1f ms, frame %.1f ms; frames waited "
          "median %.1f ms (max %.1f; %d of %d over 1 ms); switch %.1f ms; waits longer than the "
          "step's read + build: %d" % (name, dims, size, v["read_ms"], v["build_ms"], v["frame_ms"],
          v["wait_ms"], v["wait_ms_max"], v["frames_waiting_over_1ms"], len(per_step),
          v["switch_ms"], len(over)))
json.dump(figure, open(target, "w"), indent=1)
PY
  local dat="$work/timeseries.dat"
  /usr/bin/python3 - "$results/timeseries.json" >"$dat" <<'PY'
import json, sys
for v in json.load(open(sys.argv[1]))["variants"]:
    print('"%s" %g %g %g %g %g' % (v["variant"], v["read_ms"], v["build_ms"], v["wait_ms"],
                                    v["switch_ms"], v["frame_ms"]))
PY
  plot timeseries <(cat <<GP
set title "Time series, one step a frame, --bricks 4 on 3 ranks: medians per step"
set ylabel "ms"; set yrange [0:*]; set key top left
set style data histogram; set style fill solid 0.6
plot '$dat' using 2:xtic(1) title "read" lc rgb "#3070b0", '' using 3 title "build" lc rgb "#30a060", \
     '' using 4 title "frame waited" lc rgb "#c04040", '' using 5 title "switch" lc rgb "#909090", \
     '' using 6 title "frame" lc rgb "#c08030"
GP
)
}
