#!/usr/bin/python3
"""The icet figure from icet_bench's output (one JSON-lines file per point, scripts/bench icet).

Per point: the median over the measured frames (warm-up left out) of each variant's total frame
time, render time and compositing overhead, the image check against the DFB, and the issue's
fields: dfb_ms / icet_ms (total) and dfb_overhead_ms / icet_overhead_ms, where IceT's number is
that of its faster strategy at the point (the stricter comparison for the DFB). Writes the JSON
and a gnuplot data file, and prints the goals, met or not:
  - DFB total <= IceT's at every point, and the median over points of IceT/DFB >= 1.2;
  - DFB overhead <= half of IceT's at 4 and 8 ranks.
"""
import argparse
import json
import statistics

VARIANTS = ("dfb", "icet-reduce", "icet-radixk")


def point_of(path):
    lines = [json.loads(l) for l in open(path) if l.startswith("{")]
    frames = [l for l in lines if "variant" in l and not l["warmup"]]
    checks = {l["image_check"]["variant"]: l["image_check"] for l in lines if "image_check" in l}
    first = frames[0]
    p = {"ranks": first["ranks"], "width": first["width"], "height": first["height"],
         "mode": first["mode"], "tiles": first["tiles"], "frames": len(frames) // len(VARIANTS),
         "variants": {}}
    for v in VARIANTS:
        mine = [l for l in frames if l["variant"] == v]
        p["variants"][v] = {
            "median_total_ms": statistics.median(l["total_ms"] for l in mine),
            "median_render_ms": statistics.median(l["render_ms"] for l in mine),
            "median_overhead_ms": statistics.median(l["overhead_ms"] for l in mine),
            "total_ms": [round(l["total_ms"], 3) for l in mine],
            "overhead_ms": [round(l["overhead_ms"], 3) for l in mine]}
        if v in checks:
            p["variants"][v]["image_max_abs_diff"] = checks[v]["max_abs_diff"]
            p["variants"][v]["image_diff_units"] = checks[v]["units"]
            p["variants"][v]["image_pixels_over_tolerance"] = checks[v]["pixels_over_tolerance"]
    icet = [p["variants"][v] for v in VARIANTS[1:]]
    p["dfb_ms"] = p["variants"]["dfb"]["median_total_ms"]
    p["icet_ms"] = min(v["median_total_ms"] for v in icet)
    p["dfb_overhead_ms"] = p["variants"]["dfb"]["median_overhead_ms"]
    p["icet_overhead_ms"] = min(v["median_overhead_ms"] for v in icet)
    p["dfb_render_share"] = p["variants"]["dfb"]["median_render_ms"] / p["dfb_ms"]
    return p


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--machine", required=True)
    ap.add_argument("--load", required=True)
    ap.add_argument("--json", required=True)
    ap.add_argument("--dat", required=True)
    ap.add_argument("runs", nargs="+")
    a = ap.parse_args()
    points = [point_of(r) for r in a.runs]

    def label(p):
        return f'{p["ranks"]}r {p["width"]} {p["mode"][:6]} {p["tiles"]}'

    with open(a.dat, "w") as dat:
        for p in points:
            v = p["variants"]
            dat.write('"%s" %s\n' % (label(p), " ".join(
                "%.4g" % v[k][f] for f in ("median_total_ms", "median_overhead_ms")
                for k in VARIANTS)))
    ratios = [p["icet_ms"] / p["dfb_ms"] for p in points]
    slower = [label(p) for p in points if p["dfb_ms"] > p["icet_ms"]]
    overhead_points = [p for p in points if p["ranks"] in (4, 8)]
    overhead_missed = [label(p) for p in overhead_points
                       if p["dfb_overhead_ms"] > 0.5 * p["icet_overhead_ms"]]
    median_ratio = statistics.median(ratios)
    goals = {
        "dfb_total_le_icet_at_every_point": not slower,
        "points_where_dfb_total_is_slower": slower,
        "median_icet_over_dfb_total": round(median_ratio, 4),
        "median_speedup_ge_1_2": median_ratio >= 1.2,
        "dfb_overhead_le_half_icet_at_4_and_8_ranks": not overhead_missed,
        "points_where_dfb_overhead_is_over_half": overhead_missed,
        "median_dfb_render_share_of_total": round(
            statistics.median(p["dfb_render_share"] for p in points), 4),
    }
    out = {"figure": "icet", "machine": json.loads(a.machine), "load_average": a.load,
           "setup": {
               "scene": "builtin:wavelet, gradient background replaced by its middle colour; "
                        "transparent: volume + 2 isosurfaces blended in visibility order; "
                        "opaque: both isosurfaces opaque, volume hidden, z-buffer",
               "bricks": "one per rank, 1 TBB thread per rank, 2 cores (4 and 8 ranks oversubscribed)",
               "icet": "commit 088aa5a; icet-reduce = REDUCE with its default single-image "
                       "strategy, icet-radixk = REDUCE with radix-k; icet_ms / icet_overhead_ms "
                       "= the faster of the two at each point",
               "tiles": "1x1: image on rank 0 (DFB gather, RGBAF32 transparent / RGBA8 opaque); "
                        "2x2: 4 displays on ranks 0-3 (IceT tiles; DFB routes RGBA8 pieces, "
                        "format NONE, as dfbwall's route mode)",
               "overhead": "slowest rank's last local render -> finished image on every display "
                           "rank (paper 6.2.1), from steady-clock timestamps"},
           "goals": goals, "points": points}
    with open(a.json, "w") as f:
        json.dump(out, f, indent=1)
    for p in points:
        v = p["variants"]
        print("  %-28s total dfb %8.1f  reduce %8.1f  radixk %8.1f ms | overhead dfb %7.2f"
              "  reduce %7.2f  radixk %7.2f ms | image diff %s / %s" % (
                  label(p), v["dfb"]["median_total_ms"], v["icet-reduce"]["median_total_ms"],
                  v["icet-radixk"]["median_total_ms"], v["dfb"]["median_overhead_ms"],
                  v["icet-reduce"]["median_overhead_ms"], v["icet-radixk"]["median_overhead_ms"],
                  v["icet-reduce"].get("image_max_abs_diff"),
                  v["icet-radixk"].get("image_max_abs_diff")))
    yes = {True: "MET", False: "NOT MET"}
    print("  goal: DFB total <= IceT at every point: %s%s" % (
        yes[not slower], "" if not slower else " (slower at: " + ", ".join(slower) + ")"))
    print("  goal: median IceT/DFB total >= 1.2: %s (%.3f; rendering is %.1f%% of the DFB's "
          "frame, median)" % (yes[median_ratio >= 1.2], median_ratio,
                              100 * goals["median_dfb_render_share_of_total"]))
    print("  goal: DFB overhead <= half of IceT's at 4 and 8 ranks: %s%s" % (
        yes[not overhead_missed],
        "" if not overhead_missed else " (missed at: " + ", ".join(overhead_missed) + ")"))


if __name__ == "__main__":
    main()
