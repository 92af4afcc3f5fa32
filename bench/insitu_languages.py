"""Per-frame cost of the same in-situ frame from C++, C and Python (bench/api/): every frame the
program gives its borrowed slab again and renders it (a new scene version), timed on render rank
0 around clear_bricks + add_brick + render_frame: wall time, and the process's CPU time (all its
threads; on a shared machine less hit by the others' load than wall time). The three programs
run interleaved (C++ C Python C++ C Python ...), each under mpirun on RANKS ranks; each run's
first frame (start-up) is left out. Prints the medians, MADs and the ratios to C++ (goal: C and
Python within 2%), checks the three last images are the same bytes, and writes the figure's
JSON.
  python3 bench/insitu_languages.py BUILD OUT.json [--quick] [--machine JSON]"""
import json
import os
import subprocess
import sys
import tempfile


# Per frame: wall time, the process's CPU time, and the wall time of clear_bricks + add_brick.
KEYS = ("frame_ms", "cpu_ms", "calls_ms")


def median(values):
    v = sorted(values)
    n = len(v)
    return 0.0 if n == 0 else (v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    quick = "--quick" in sys.argv
    machine = {}
    if "--machine" in sys.argv:
        machine = json.loads(sys.argv[sys.argv.index("--machine") + 1])
        args.remove(sys.argv[sys.argv.index("--machine") + 1])
    build, out = args[0], args[1]
    grid, frames, size, ranks = (64, 10, "320x240", 2) if quick else (96, 20, "480x360", 2)
    rounds = 2 if quick else 4
    here = os.path.dirname(os.path.abspath(__file__))
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               PYTHONPATH=os.path.join(build, "python"))
    programs = {
        "c++": [os.path.join(build, "bench", "api", "insitu_frame_bench")],
        "c": [os.path.join(build, "bench", "api", "insitu_frame_bench_c")],
        "python": [sys.executable, os.path.join(here, "api", "insitu_frame_bench.py")],
    }
    times = {name: {key: [] for key in KEYS} for name in programs}
    images = {}
    work = tempfile.mkdtemp(prefix="dfbwall-languages.")
    print("== languages: the in-situ frame (a %d^3 field in %d borrowed slabs, %s, 1 thread per "
          "rank) from C++, C and Python, %d interleaved runs of %d frames"
          % (grid, ranks, size, rounds, frames))
    for r in range(rounds):
        for name, command in programs.items():
            image = os.path.join(work, "%s.png" % name.replace("+", "p"))
            run = subprocess.run(["mpiexec", "-n", str(ranks), "--oversubscribe", "--bind-to", "none"]
                                 + command + [str(grid), str(frames), size, image],
                                 env=env, capture_output=True, text=True, timeout=600)
            if run.returncode != 0:
                sys.exit("%s failed:\n%s%s" % (name, run.stdout, run.stderr))
            line = next(l for l in run.stdout.splitlines() if l.startswith("{"))
            run_times = json.loads(line)
            for key in KEYS:
                times[name][key] += run_times[key][1:]
            with open(image, "rb") as f:
                images[name] = f.read()
    base = {key: median(times["c++"][key]) for key in KEYS}
    variants = []
    for name, t in times.items():
        variant = {"language": name}
        line = "  %-7s" % name
        for key in KEYS:
            m = median(t[key])
            mad = median([abs(v - m) for v in t[key]])
            variant[key] = {"median": m, "mad": mad, "frames": len(t[key]),
                            "ratio_to_cpp": m / base[key]}
            line += "  %s %8.3f (MAD %6.3f) %.3f x" % (key, m, mad, m / base[key])
        variants.append(variant)
        print(line)
    same = images["c"] == images["c++"] and images["python"] == images["c++"]
    print("  the three last frames are %s" % ("the same bytes" if same else "DIFFERENT"))
    # What the language adds per frame, rendering aside, against the frame: the bound that does
    # not drown in a loaded machine's noise as whole-frame ratios do.
    for v in variants:
        extra = v["calls_ms"]["median"] - base["calls_ms"]
        v["calls_over_cpp_share_of_frame"] = extra / base["frame_ms"]
        print("  %-7s clear_bricks + add_brick: %+.4f ms against C++ = %+.3f%% of a frame"
              % (v["language"], extra, 100 * extra / base["frame_ms"]))
    print("  goal: C and Python within 2% of C++ per frame")
    with open(out, "w") as f:
        json.dump({"figure": "languages", "machine": machine,
                   "setup": {"grid": grid, "ranks": ranks, "size": size, "frames": frames,
                             "rounds": rounds, "threads_per_rank": 1, "borrowed": True},
                   "variants": variants, "images_equal": same,
                   "goals": ["C and Python within 2% of C++ per frame"]}, f, indent=1)
    if not same:
        sys.exit("the languages rendered different images")


main()
