#!/usr/bin/python3
"""Figure "control" of scripts/bench: how fast a steering request reaches every display.

For frames in flight K = 1, 2, 3 and two renderers (the pattern: fast frames, delivery-bound;
the path tracer: render-bound), a 2x2 wall (2 render + 4 wall ranks, OSMesa) runs until stopped
(--frames 0) with the control API; camera requests (orbit 3 degrees) arrive at random moments,
and the statistics say for each request the frame that first showed it on every display, how
many frames the displays presented from the request to it (request_to_displays_frames; the
claim: at most K + 1) and how long it took (request_to_displays_ms, rank 0's clock: from the
request's arrival to the wall's acknowledgement that every display presented it). Variants run
interleaved (A B C ... A B C ...). Also: CPU per rank once converged (idle) and the time from a
request to every display when the wall was idle.

  control_bench.py DFBWALL WALL_LAYOUT OUT.json [--quick]
"""
import json
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

# The control API's token, given through the environment as an operator would.
TOKEN = os.urandom(16).hex()
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           DFBWALL_CONTROL_TOKEN=TOKEN)
AUTH = {"Authorization": "Bearer " + TOKEN}


def post(url, path, body):
    req = urllib.request.Request(url + path, data=json.dumps(body).encode(), method="POST",
                                 headers=AUTH)
    with urllib.request.urlopen(req, timeout=10) as r:
        return json.loads(r.read())


def get(url, path):
    with urllib.request.urlopen(urllib.request.Request(url + path, headers=AUTH),
                                timeout=10) as r:
        return json.loads(r.read())


def start(dfbwall, wall, stats, *args):
    p = subprocess.Popen(["mpiexec", "-n", "6", "--oversubscribe", "--bind-to", "none", dfbwall,
                          "--wall", wall, "--offscreen", "--frames", "0", "--quiet", "--control",
                          "127.0.0.1:0", "--stats", stats, *args],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=ENV)
    for line in p.stdout:
        m = re.search(r"control API on (http://\S+?)/", line)
        if m:
            threading.Thread(target=lambda: [None for _ in p.stdout], daemon=True).start()
            return p, m.group(1)
    raise SystemExit("control_bench: the job ended before its control server started")


def stop(p, url):
    post(url, "/api/stop", {})
    if p.wait(timeout=60) != 0:
        raise SystemExit("control_bench: the job failed")


def latency_run(dfbwall, wall, work, renderer, k, requests, rng):
    stats = os.path.join(work, "stats.json")
    extra = ["--renderer", renderer, "--frames-in-flight", str(k)]
    if renderer == "pathtracer":
        extra += ["--spp", "1", "--max-depth", "4"]
    p, url = start(dfbwall, wall, stats, *extra)
    while get(url, "/api/status")["presented"] < 3:  # past start-up
        time.sleep(0.05)
    for _ in range(requests):
        time.sleep(rng.uniform(0.1, 0.3))
        post(url, "/api/camera", {"orbit": 3})
    time.sleep(0.5)
    stop(p, url)
    lines = [json.loads(line) for line in open(stats)]
    frames = [line for line in lines if "frame" in line and "frame_ms" in line]
    applied = [f for f in frames if "request_to_displays_frames" in f]
    return {
        "frame_ms": [f["frame_ms"] for f in frames[1:]],
        "request_frames": [f["request_to_displays_frames"] for f in applied],
        "request_ms": [f["request_to_displays_ms"] for f in applied],
    }


def cpu_seconds(pid):
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def idle_run(dfbwall, wall, work, seconds):
    stats = os.path.join(work, "idle.json")
    p, url = start(dfbwall, wall, stats, "--renderer", "pathtracer", "--spp", "2",
                   "--max-spp", "8", "--max-depth", "4")
    while not get(url, "/api/status")["idle"]:
        time.sleep(0.05)
    time.sleep(0.5)
    with open("/proc/%d/task/%d/children" % (p.pid, p.pid)) as f:
        pids = [int(x) for x in f.read().split()]
    before = {q: cpu_seconds(q) for q in pids}
    t0 = time.time()
    time.sleep(seconds)
    elapsed = time.time() - t0
    shares = [(cpu_seconds(q) - before[q]) / elapsed for q in pids]
    t0 = time.time()
    request = post(url, "/api/camera", {"orbit": 10})["request"]
    while True:
        s = get(url, "/api/status")
        if s["last_request"]["id"] >= request and s["presented"] >= s["last_request"]["frame"]:
            break
        time.sleep(0.005)
    wake_ms = 1000 * (time.time() - t0)
    stop(p, url)
    return {"idle_cpu_share_per_rank": shares, "idle_seconds": elapsed, "wake_to_displays_ms":
            wake_ms}


def summary(values):
    if not values:
        return {"median": 0, "mad": 0, "max": 0, "count": 0}
    m = statistics.median(values)
    return {"median": m, "mad": statistics.median(abs(v - m) for v in values),
            "max": max(values), "count": len(values)}


def main():
    dfbwall, wall, out = sys.argv[1:4]
    quick = "--quick" in sys.argv[4:]
    reps, requests = (1, 6) if quick else (3, 10)
    rng = random.Random(12)
    variants = [(r, k) for r in ("pattern", "pathtracer") for k in (1, 2, 3)]
    runs = {v: [] for v in variants}
    load0 = open("/proc/loadavg").read().split()[:3]
    with tempfile.TemporaryDirectory() as work:
        for _ in range(reps):
            for v in variants:  # interleaved
                runs[v].append(latency_run(dfbwall, wall, work, v[0], v[1], requests, rng))
        idle = idle_run(dfbwall, wall, work, 3 if quick else 5)
    result = {"layout": os.path.basename(wall), "ranks": {"render": 2, "wall": 4},
              "load_before": load0, "load_after": open("/proc/loadavg").read().split()[:3],
              "variants": [], "idle": idle}
    print("control: request -> every display, 2x2 wall (2 render + 4 wall ranks, OSMesa)")
    for (renderer, k), rs in runs.items():
        frames = [x for r in rs for x in r["request_frames"]]
        ms = [x for r in rs for x in r["request_ms"]]
        frame_ms = [x for r in rs for x in r["frame_ms"]]
        entry = {"renderer": renderer, "frames_in_flight": k, "bound_frames": k + 1,
                 "request_frames": summary(frames), "request_ms": summary(ms),
                 "frame_ms": summary(frame_ms),
                 "within_bound": all(f <= k + 1 for f in frames)}
        result["variants"].append(entry)
        print("  %-10s K=%d: %2d requests, frames to every display median %.0f max %d (bound %d)"
              ", %.1f ms median (frame %.1f ms)" %
              (renderer, k, len(frames), entry["request_frames"]["median"],
               entry["request_frames"]["max"], k + 1, entry["request_ms"]["median"],
               entry["frame_ms"]["median"]))
    print("  idle (converged) CPU per rank over %.1f s: %s of one core; a request then reached "
          "every display in %.0f ms" %
          (idle["idle_seconds"], " ".join("%.3f" % s for s in idle["idle_cpu_share_per_rank"]),
           idle["wake_to_displays_ms"]))
    with open(out, "w") as f:
        json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
