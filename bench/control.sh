# Figure "control" of scripts/bench (sourced by it; uses its helpers and variables): steering a
# running wall. bench/control_bench.py drives a 2x2 wall (configs/walls/2x2.toml,
# 2 render + 4 wall ranks, OSMesa) through the control API: camera requests at random moments
# for frames in flight K = 1, 2, 3 with the pattern (delivery-bound) and the path tracer
# (render-bound), interleaved; the statistics give, per request, the frames the displays
# presented from the request to the first frame showing it (claim: at most K + 1) and the time.
# Then idle: CPU per rank once converged (--max-spp), and a request's time to every display
# from idle. About 2 minutes; --quick about 1.
fig_control() {
  echo "== control: request -> every display on a 2x2 wall, K = 1, 2, 3 frames in flight"
  local out="$work/control-raw.json"
  /usr/bin/python3 "$root/bench/control_bench.py" "$dfbwall" "$root/configs/walls/2x2.toml" "$out" \
    $([ $quick = 1 ] && echo --quick)
  /usr/bin/python3 - "$out" "$results/control.json" "$machine" <<'PY'
import json, sys
raw = json.load(open(sys.argv[1]))
json.dump({"figure": "control", "machine": json.loads(sys.argv[3]), **raw}, open(sys.argv[2], "w"),
          indent=1)
PY
  local dat="$work/control.dat"
  /usr/bin/python3 - "$out" >"$dat" <<'PY'
import json, sys
for v in json.load(open(sys.argv[1]))["variants"]:
    print('"%s K=%d" %g %g %d' % (v["renderer"], v["frames_in_flight"], v["request_frames"]["median"],
                                  v["request_frames"]["max"], v["bound_frames"]))
PY
  plot control <(cat <<GP
set title "Steering request -> every display, 2x2 wall (2 render + 4 wall ranks)"
set ylabel "frames presented from the request to the change"; set yrange [0:*]; set key top left
set style data histogram; set style fill solid 0.6; set xtics rotate by -20
plot '$dat' using 2:xtic(1) title "median" lc rgb "#3070b0", \
     '' using 3 title "max" lc rgb "#c08030", '' using 4 title "bound K + 1" lc rgb "#909090"
GP
)
}
