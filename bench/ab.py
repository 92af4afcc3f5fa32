#!/usr/bin/env python3
"""A/B comparison of two dfbwall builds, or two option sets, on one set-up, run interleaved.

  bench/ab.py [--reps R] [--np N] [--json FILE] \\
      --variant NAME "BINARY [ARGS]" --variant NAME "BINARY [ARGS]" -- COMMON DFBWALL ARGS

Runs A B A B ... (R rounds), so a loaded machine's noise hits every variant alike, and prints
per variant: the median frame time and its MAD (first frame of every run left out), the CPU
seconds the whole job used per frame (all ranks and threads, from the children's rusage: on a
shared machine this is steadier than elapsed time), the stage times summed over the ranks of
each role per frame (from --stats), and each variant's ratio to the first. Also the load average
before and after. Example (the delivery figure's wall, before and after a change):

  bench/ab.py --variant main /tmp/main/dfbwall --variant new build/apps/dfbwall -- \\
      --wall configs/walls/2x2-1080p.toml --offscreen --orbit 1 --renderer pattern --frames 10
"""
import argparse
import json
import os
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile


def median_mad(values):
    if not values:
        return 0.0, 0.0
    m = statistics.median(values)
    return m, statistics.median([abs(v - m) for v in values])


def run_once(np_, command, stats_path):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    cmd = ["mpiexec", "-n", str(np_), "--oversubscribe", "--bind-to", "none"] + command + [
        "--quiet", "--stats", stats_path]
    subprocess.run(cmd, env=env, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    frames, stages, spreads = [], {}, []
    with open(stats_path) as f:
        for line in f:
            record = json.loads(line)
            if "frame" in record and "frame_ms" in record:
                frames.append(record["frame_ms"])
            elif "stages_ms" in record:
                for stage, ms in record["stages_ms"].items():
                    key = record["role"] + "." + stage
                    stages[key] = stages.get(key, 0.0) + ms
                if "swap_spread_ms" in record:  # the same on every wall rank
                    spread = record["swap_spread_ms"]
                    spreads.append((spread["max"], spread["mean"]))
    return frames, stages, cpu, spreads[:1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--np", type=int, default=6)
    parser.add_argument("--json")
    parser.add_argument("--variant", nargs=2, action="append", metavar=("NAME", "COMMAND"),
                        required=True)
    parser.add_argument("common", nargs=argparse.REMAINDER)
    a = parser.parse_args()
    common = a.common[1:] if a.common[:1] == ["--"] else a.common
    load_before = os.getloadavg()
    results = {name: {"frames": [], "stages": {}, "cpu_s": 0.0, "frame_count": 0,
                      "swap_spread": [], "cpu_ms_per_frame_by_run": []}
               for name, _ in a.variant}
    with tempfile.TemporaryDirectory() as work:
        for rep in range(a.reps):
            for name, command in a.variant:
                stats = os.path.join(work, f"{name}-{rep}.json")
                frames, stages, cpu, spread = run_once(a.np, shlex.split(command) + common,
                                                       stats)
                results[name]["swap_spread"] += spread
                r = results[name]
                r["frames"] += frames[1:]
                r["frame_count"] += len(frames)
                r["cpu_s"] += cpu
                r["cpu_ms_per_frame_by_run"].append(1000 * cpu / max(1, len(frames)))
                for k, v in stages.items():
                    r["stages"][k] = r["stages"].get(k, 0.0) + v
    load_after = os.getloadavg()
    out = {"common": common, "np": a.np, "reps": a.reps,
           "load_before": load_before, "load_after": load_after, "variants": []}
    first = None
    for name, command in a.variant:
        r = results[name]
        med, mad = median_mad(r["frames"])
        n = max(1, r["frame_count"])
        row = {"name": name, "command": command, "median_frame_ms": med, "mad_frame_ms": mad,
               "frames": len(r["frames"]), "cpu_ms_per_frame": 1000 * r["cpu_s"] / n,
               "cpu_ms_per_frame_by_run": r["cpu_ms_per_frame_by_run"],
               "stages_ms_per_frame": {k: v / n for k, v in sorted(r["stages"].items())}}
        if r["swap_spread"]:  # builds that measure it: per run (max, mean)
            row["swap_spread_ms_max"] = max(m for m, _ in r["swap_spread"])
            row["swap_spread_ms_mean"] = statistics.mean(x for _, x in r["swap_spread"])
        if first is None:
            first = row
        row["frame_ms_ratio_to_first"] = med / first["median_frame_ms"] if first[
            "median_frame_ms"] else 0
        row["cpu_ratio_to_first"] = row["cpu_ms_per_frame"] / first["cpu_ms_per_frame"] if first[
            "cpu_ms_per_frame"] else 0
        out["variants"].append(row)
    print(f"load average before {load_before[0]:.1f}, after {load_after[0]:.1f}; "
          f"{a.reps} interleaved rounds, {a.np} ranks")
    for row in out["variants"]:
        print(f"{row['name']}: frame {row['median_frame_ms']:.1f} ms (MAD "
              f"{row['mad_frame_ms']:.1f}, {row['frames']} frames, x"
              f"{row['frame_ms_ratio_to_first']:.3f}), CPU {row['cpu_ms_per_frame']:.1f} ms/frame "
              f"(x{row['cpu_ratio_to_first']:.3f}; runs: "
              + " ".join(f"{c:.0f}" for c in row["cpu_ms_per_frame_by_run"]) + ")")
        if "swap_spread_ms_max" in row:
            print(f"   swaps of one frame across wall ranks: mean spread "
                  f"{row['swap_spread_ms_mean']:.2f} ms, max {row['swap_spread_ms_max']:.2f} ms")
        print("   " + ", ".join(f"{k} {v:.2f}" for k, v in row["stages_ms_per_frame"].items()))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
