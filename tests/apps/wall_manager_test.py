#!/usr/bin/python3
"""The wall's window manager (serve --control; docs/service.md, "The wall's control page") on a
real service wall: a 2x2 OSMesa wall, `serve --max-jobs 2 --control --capture`, two jobs of the
primary renderer (the same picture every frame) in overlapping windows across display borders.

  wall_manager_test.py LAYOUT (the 2x2 wall)

 - GET /api/wall: canvas, displays, background, max jobs; GET /api/windows: both windows with
   their rectangles, z (the newest on top), running, frames and rate growing, job a's page;
 - POST {"raise": true} puts job a's window on top (z), and on the wall: a Raise reaches every
   process, and the wall's own captures, which showed b over a (and never a over b) before,
   show a over b (the composite, compare_captures --composite) without either job restarting;
 - bad bodies and rectangles 400, unknown windows 404;
 - attacks: no token, a wrong token, a rebinding Host, the page's cookie without JSON or from
   another Origin, a body over 64 KiB: refused, nothing changed; then a good client still works;
 - POST {"x", "y", "w", "h"} moves and resizes job a's window, then job b's: GET /api/windows
   shows each new rectangle, each job re-plans without reconnecting, its captures from the
   switch frame on equal the one-process render at the new size; job a's own page follows
   (/api/layout is the new window's, /api/preview.png the new window's render where displays
   are); the wall's own captures show both at their new places;
 - GET /api/windows/ID/thumbnail (`--thumbnail-size 64`): each window's live thumbnail, a PNG
   assembled on the head from every process's cell sums, equals the box filter (factor 4) of
   the window's one-process render over the pixels displays show, exactly (compare_captures
   --thumbnail); after window 2's move, the new window's; unknown windows 404, no token 401;
 - DELETE of job b's window: b exits non-zero saying "closed from the wall's control page" on
   its rank 0, its window leaves the list at once, and job a keeps presenting new frames.
Needs DFBWALL, COMPARE and MPIEXEC in the environment.
"""
import http.client
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

DFBWALL, COMPARE, MPIEXEC = os.environ["DFBWALL"], os.environ["COMPARE"], os.environ["MPIEXEC"]
SCALE = int(os.environ.get("DFBWALL_TIME_SCALE", "1"))
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
MPI = [MPIEXEC, "--oversubscribe", "--bind-to", "none", "--mca", "mpi_yield_when_idle", "1"]
WINDOW_A, WINDOW_B = "90,70,250,170", "20,20,200,150"
MOVED_A = "100,80,260,180"  # job a's window after its move (a job with its own page and preview)
MOVED_B = "150,100,240,180"  # job b's window after its move: elsewhere and larger
THUMBNAIL_SIDE = 64  # serve --thumbnail-size: factor 4 for both windows, cells cut by bezels


class Test:
    def __init__(self, layout):
        self.layout = layout
        self.work = tempfile.mkdtemp(prefix="wall-manager-")
        self.procs = {}

    def start(self, name, args):
        out = open(os.path.join(self.work, name + ".out"), "w")
        self.procs[name] = subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT, env=ENV,
                                            start_new_session=True)
        return self.procs[name]

    def log(self, name):
        try:
            with open(os.path.join(self.work, name + ".out")) as f:
                return f.read()
        except OSError:
            return ""

    def fail(self, why):
        print("FAIL: " + why)
        for name in self.procs:
            print("--- %s:\n%s" % (name, self.log(name)))
        self.cleanup()
        sys.exit(1)

    def cleanup(self):
        for p in self.procs.values():
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
        if not os.environ.get("KEEP"):
            shutil.rmtree(self.work, ignore_errors=True)

    def wait_for(self, what, check, seconds):
        end = time.time() + seconds * SCALE
        while time.time() < end:
            value = check()
            if value:
                return value
            time.sleep(0.1)
        self.fail("timed out waiting for " + what)

    def newest(self, job, display):
        folder = os.path.join(self.work, "jobs", job, display)
        frames = [int(f[6:12]) for f in os.listdir(folder)
                  if re.fullmatch(r"frame-\d{6}\.png", f)] if os.path.isdir(folder) else []
        return max(frames, default=0)

    def captured(self, job, frame):
        """Frame FRAME of job JOB is captured whole: every display folder's and the wall
        preview (each process writes its own displays, the job's rank 0 the preview)."""
        folder = os.path.join(self.work, "jobs", job)
        name = "frame-%06d.png" % frame
        displays = [d for d in os.listdir(folder) if os.path.isdir(os.path.join(folder, d))]
        return bool(displays) and os.path.exists(os.path.join(folder, "wall-%06d.png" % frame)) \
            and all(os.path.exists(os.path.join(folder, d, name)) for d in displays)


class Http:
    """Requests with exactly the headers given."""

    def __init__(self, port, token):
        self.port, self.token = port, token
        self.own = "127.0.0.1:%d" % port

    def send(self, method, path, headers=None, body=None, auth=True, host=None):
        connection = http.client.HTTPConnection("127.0.0.1", self.port, timeout=10)
        connection.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
        sent = {"Host": host or self.own}
        if auth:
            sent["Authorization"] = "Bearer " + self.token
        sent.update(headers or {})
        for name, value in sent.items():
            if value is not None:
                connection.putheader(name, value)
        if body is not None:
            body = body.encode() if isinstance(body, str) else body
            connection.putheader("Content-Length", str(len(body)))
        connection.endheaders(body)
        response = connection.getresponse()
        payload = response.read()
        connection.close()
        try:
            parsed = json.loads(payload)
        except ValueError:
            parsed = payload
        return response.status, response.headers, parsed

    def get(self, path):
        return self.send("GET", path)


def main():
    t = Test(sys.argv[1])
    try:
        run(t)
    except SystemExit:
        raise
    except BaseException as e:  # noqa: B902 (a Python error fails the test with the logs)
        t.fail("%s: %s" % (type(e).__name__, e))
    t.cleanup()


def run(t):
    port = 20000 + os.getpid() % 20000
    control = port + 1
    token_file = os.path.join(t.work, "wall-control-token")
    jobs, wall_captures = os.path.join(t.work, "jobs"), os.path.join(t.work, "wall")
    os.mkdir(jobs)  # the jobs' capture root; the wall's own captures outside it
    processes = int(subprocess.check_output([COMPARE, "--info", t.layout]).split()[0])
    serve = t.start("serve", MPI + [
        "-np", str(processes), DFBWALL, "serve", "--wall", t.layout, "--listen",
        "127.0.0.1:%d" % port, "--offscreen", "--timeout", str(8 * SCALE), "--capture-root",
        jobs, "--capture", wall_captures, "--capture-every", "4", "--max-jobs", "2", "--background", "#000000", "--control",
        "127.0.0.1:%d" % control, "--control-token-file", token_file, "--thumbnail-size",
        str(THUMBNAIL_SIDE)])
    t.wait_for("serve to start", lambda: "window manager:" in t.log("serve"), 20)
    line = re.search(r"window manager: control API on (http://\S+)", t.log("serve"))
    if not line or line.group(1) != "http://127.0.0.1:%d/" % control:
        t.fail("serve did not print the window manager's address")
    if open(token_file).read().strip() in t.log("serve"):
        t.fail("serve printed the token of its --control-token-file")
    api = Http(control, open(token_file).read().strip())

    status, _, wall = api.get("/api/wall")
    if status != 200 or wall["canvas"] != {"w": 412, "h": 310} or len(wall["displays"]) != 4 or \
            wall["background"] != "#000000" or wall["max_jobs"] != 2:
        t.fail("GET /api/wall: %d %r" % (status, wall))
    if wall["displays"][0] != {"name": "r0c0", "rect": {"x": 0, "y": 0, "w": 200, "h": 150},
                               "process": 0}:
        t.fail("GET /api/wall: display 0 is %r" % wall["displays"][0])
    if api.get("/api/windows")[2] != []:
        t.fail("windows before any job")

    # One-process renders of both windows (and of b's after its move), for the jobs' and the
    # wall's captures.
    ref_a, ref_b = os.path.join(t.work, "ref-a.png"), os.path.join(t.work, "ref-b.png")
    ref_moved = os.path.join(t.work, "ref-b-moved.png")
    ref_moved_a = os.path.join(t.work, "ref-a-moved.png")
    for size, ref in [("250x170", ref_a), ("200x150", ref_b),
                      ("%sx%s" % tuple(MOVED_B.split(",")[2:]), ref_moved),
                      ("%sx%s" % tuple(MOVED_A.split(",")[2:]), ref_moved_a)]:
        subprocess.check_call(MPI + ["-np", "1", DFBWALL, "--renderer", "primary", "--size", size,
                                     "--frames", "1", "--quiet", "--image", ref], env=ENV)
    job = ["--renderer", "primary", "--frames", "100000", "--capture-every", "10", "--quiet",
           "--timeout", "30"]
    # Job a has a page (--control), on two ranks: its preview's cells travel from both.
    t.start("a", MPI + ["-np", "2", DFBWALL, "--connect", "127.0.0.1:%d" % port, "--window",
                        WINDOW_A, "--capture", os.path.join(jobs, "a"), "--control",
                        "127.0.0.1:0", "--control-token-file",
                        os.path.join(t.work, "job-token")] + job)
    t.wait_for("job a's frame 10", lambda: t.newest("a", "r1c1") >= 10, 20)
    t.start("b", MPI + ["-np", "2", DFBWALL, "--connect", "127.0.0.1:%d" % port, "--window",
                        WINDOW_B, "--capture", os.path.join(jobs, "b")] + job)
    t.wait_for("job b's frame 10", lambda: t.newest("b", "r0c0") >= 10, 20)

    # Both windows, the newest on top.
    windows = api.get("/api/windows")[2]
    if [w["id"] for w in windows] != ["1", "2"]:
        t.fail("GET /api/windows: %r" % windows)
    a, b = windows
    if a["rect"] != {"x": 90, "y": 70, "w": 250, "h": 170} or \
            b["rect"] != {"x": 20, "y": 20, "w": 200, "h": 150}:
        t.fail("window rectangles: %r" % windows)
    if (a["z"], b["z"]) != (0, 1) or a["state"] != "running" or b["state"] != "running":
        t.fail("z and state: %r" % windows)
    if a["host"] == "" or a["job"] != "primary builtin:cornell" or b["page"] is not None:
        t.fail("host, job, page: %r" % windows)
    page = re.search(r"control API on (http://127\.0\.0\.1:\d+/)", t.log("a"))
    if not page or a["page"] != page.group(1):
        t.fail("job a's page is %r, its log says %r" % (a["page"], page and page.group(1)))
    time.sleep(1)
    later = api.get("/api/windows")[2]
    if later[0]["frames"] <= a["frames"] or later[0]["fps"] <= 0 or later[1]["fps"] <= 0:
        t.fail("frames and rates do not grow: %r then %r" % (windows, later))

    # Each window's thumbnail: the box filter of its own render (what it shows, not what covers
    # it), assembled from the cells of every process whose displays it crosses.
    for number, window, ref in [("1", WINDOW_A, ref_a), ("2", WINDOW_B, ref_b)]:
        t.wait_for("window %s's thumbnail" % number,
                   lambda: thumbnail_is(t, api, number, window, ref), 10)
    status, headers, _ = api.get("/api/windows/1/thumbnail")
    if headers["Content-Type"] != "image/png" or headers["X-Content-Type-Options"] != "nosniff" \
            or headers["Cache-Control"] != "no-store":
        t.fail("the thumbnail's headers: %r" % dict(headers))
    for path, expected in [("/api/windows/3/thumbnail", 404), ("/api/windows/x/thumbnail", 404),
                           ("/api/windows//thumbnail", 404)]:
        if api.get(path)[0] != expected:
            t.fail("GET %s: %d, expected %d" % (path, api.get(path)[0], expected))
    if api.send("GET", "/api/windows/1/thumbnail", auth=False)[0] != 401:
        t.fail("a thumbnail without the token")

    # The wall shows b over a (the newer on top), never a over b so far.
    b_over_a = lambda: composite(t, WINDOW_A + "+" + WINDOW_B, ref_a + "+" + ref_b, wall_captures)
    a_over_b = lambda: composite(t, WINDOW_B + "+" + WINDOW_A, ref_b + "+" + ref_a, wall_captures)
    t.wait_for("the wall's captures of b over a", b_over_a, 10)
    if a_over_b():
        t.fail("the wall showed window a over b before any raise")

    # Raise job a: on top; b under it, in the list and on the wall's captures. Raising the top
    # window again changes nothing.
    status, _, body = api.send("POST", "/api/windows/1", body='{"raise": true}')
    if status != 200 or body != {"id": "1", "raised": True}:
        t.fail("raise: %d %r" % (status, body))
    z = {w["id"]: w["z"] for w in api.get("/api/windows")[2]}
    if z != {"1": 1, "2": 0}:
        t.fail("z after raising window 1: %r" % z)
    raised_at = time.time()
    t.wait_for("the wall's captures of a over b after the raise", a_over_b, 10)
    shown = time.time() - raised_at
    if api.send("POST", "/api/windows/1", body='{"raise": true}')[0] != 200:
        t.fail("raising the top window again")
    # Refused bodies and windows.
    for body, expected in [('{"x": 300}', 400), ('{"w": 0}', 400), ('{"x": 1.5}', 400),
                           ('{"x": 10, "raise": true}', 400), ('{"fullscreen": false}', 400),
                           ('{"w": 8, "h": 8}', 400), ('{"raise": false}', 400),
                           ('{"nope": 1}', 400), ('raise', 400), ('[]', 400), ('{}', 400),
                           (None, 400)]:
        status, _, reply = api.send("POST", "/api/windows/2", body=body)
        if status != expected or "error" not in reply:
            t.fail("POST %r: %d %r, expected %d" % (body, status, reply, expected))
    for path in ["/api/windows/3", "/api/windows/01", "/api/windows/x", "/api/windows/-1",
                 "/api/windows/99999999999999999999999"]:
        status, _, reply = api.send("POST", path, body='{"raise": true}')
        if status != 404:
            t.fail("POST %s: %d %r" % (path, status, reply))
        if api.send("DELETE", path)[0] != 404:
            t.fail("DELETE %s was not 404" % path)
    if api.send("PUT", "/api/windows/1", body="{}")[0] != 405:
        t.fail("PUT was not 405")

    # Attacks: each refused, nothing changed.
    attacks = [
        ("no token", dict(method="DELETE", path="/api/windows/2", auth=False), 401),
        ("a wrong token", dict(method="DELETE", path="/api/windows/2", auth=False,
                               headers={"Authorization": "Bearer " + "0" * 32}), 401),
        ("a rebinding Host", dict(method="DELETE", path="/api/windows/2",
                                  host="evil.example:%d" % control), 403),
        ("a body over 64 KiB", dict(method="POST", path="/api/windows/2",
                                    body='{"raise": true, "pad": "' + "x" * 70000 + '"}'), 413),
    ]
    status, headers, _ = api.send("GET", "/?token=" + api.token, auth=False)
    if status != 303:
        t.fail("GET /?token= gave %d" % status)
    cookie = headers["Set-Cookie"].split(";")[0]
    for name, request, origin, kind in [
            ("the page's cookie without JSON", "DELETE", api.own, None),
            ("the page's cookie from another Origin", "DELETE", "evil.example", "application/json"),
            ("the page's cookie without an Origin", "POST", None, "application/json")]:
        attacks.append((name, dict(method=request, path="/api/windows/2", auth=False,
                                   body='{"raise": true}' if request == "POST" else None,
                                   headers={"Cookie": cookie, "Content-Type": kind,
                                            "Origin": origin and "http://" + origin}), 403))
    for name, request, expected in attacks:
        status, _, reply = api.send(**request)
        if status != expected:
            t.fail("%s: %d %r, expected %d" % (name, status, reply, expected))
    z = {w["id"]: (w["z"], w["state"]) for w in api.get("/api/windows")[2]}
    if z != {"1": (1, "running"), "2": (0, "running")}:
        t.fail("an attack changed the windows: %r" % z)
    # The page's own way works: its cookie, JSON, its Origin.
    status, _, reply = api.send("POST", "/api/windows/2", body='{"raise": true}', auth=False,
                                headers={"Cookie": cookie, "Content-Type": "application/json",
                                         "Origin": "http://" + api.own})
    if status != 200 or {w["id"]: w["z"] for w in api.get("/api/windows")[2]} != {"1": 0, "2": 1}:
        t.fail("the page's raise after the attacks: %d %r" % (status, reply))

    moved = move_windows(t, api, jobs, wall_captures, ref_moved_a, ref_moved)
    t.wait_for("window 2's thumbnail at its new size",
               lambda: thumbnail_is(t, api, "2", MOVED_B, ref_moved), 10)

    # Close job b: it ends non-zero, told why; its window leaves at once; a goes on.
    closed_at = time.time()
    status, _, reply = api.send("DELETE", "/api/windows/2")
    if status != 200 or reply != {"id": "2", "closed": True}:
        t.fail("DELETE: %d %r" % (status, reply))
    ids = [w["id"] for w in api.get("/api/windows")[2] if w["state"] != "ending"]
    if ids != ["1"]:
        t.fail("window 2 still open after its DELETE: %r" % api.get("/api/windows")[2])
    code = t.procs["b"].wait(timeout=20 * SCALE)
    if code == 0 or "closed from the wall's control page" not in t.log("b"):
        t.fail("job b: exit %d after its window was closed" % code)
    t.wait_for("window 2 to leave", lambda: [w["id"] for w in api.get("/api/windows")[2]] == ["1"],
               5)
    gone = time.time() - closed_at
    before = t.newest("a", "r1c1")
    t.wait_for("job a's next frames", lambda: t.newest("a", "r1c1") >= before + 20, 10)
    if subprocess.call([COMPARE, "--window", WINDOW_A, t.layout, os.path.join(jobs, "a"), ref_a,
                        "10"]) != 0:
        t.fail("job a's captures")

    # Stop: job a is told the wall stops.
    serve.send_signal(signal.SIGUSR1)
    if serve.wait(timeout=20 * SCALE) != 0:
        t.fail("serve exited non-zero after SIGUSR1")
    if t.procs["a"].wait(timeout=20 * SCALE) == 0:
        t.fail("job a did not hear that the wall stopped")
    print("PASS: /api/wall and /api/windows describe the wall and both windows; raise reorders "
          "them (the wall's captures show it %.2f s after the request); POSTs moved and resized "
          "windows 1 and 2 (%s); bad bodies 400, unknown windows 404; 7 attacks refused; DELETE ended "
          "job b (window gone %.2f s after the request) while job a went on (frame %d, then %d)"
          % (shown, moved, gone, before, t.newest("a", "r1c1")))


def thumbnail_is(t, api, number, window, render):
    """Window NUMBER's thumbnail is the box filter of RENDER, its window's one-process render."""
    status, headers, png = api.get("/api/windows/%s/thumbnail" % number)
    if status != 200:
        return False
    path = os.path.join(t.work, "thumbnail-%s.png" % number)
    with open(path, "wb") as f:
        f.write(png)
    return subprocess.call([COMPARE, "--thumbnail", window, t.layout, path, render,
                            str(THUMBNAIL_SIDE)], stdout=subprocess.DEVNULL) == 0


def rect_of(text):
    x, y, w, h = map(int, text.split(","))
    return {"x": x, "y": y, "w": w, "h": h}


def move_windows(t, api, jobs, wall_captures, ref_moved_a, ref_moved):
    """Moves and resizes both windows through the API; returns what it measured."""
    rects = lambda: {i["id"]: i["rect"] for i in api.get("/api/windows")[2]}
    # Job a has its own page and preview: they follow its window to the new size.
    job_page = re.search(r"control API on http://127\.0\.0\.1:(\d+)/", t.log("a"))
    page = Http(int(job_page.group(1)), open(os.path.join(t.work, "job-token")).read().strip())
    status, _, reply = api.send("POST", "/api/windows/1", body=json.dumps(rect_of(MOVED_A)))
    if status != 200 or reply != {"id": "1", "rect": rect_of(MOVED_A)}:
        t.fail("moving window 1 (a job with --control): %d %r" % (status, reply))
    t.wait_for("GET /api/windows to show window 1 moved", lambda: rects()["1"] == rect_of(MOVED_A),
               10)
    switch_a = int(t.wait_for("job a to say it moved", lambda: re.search(
        r"the wall moved the window to %s from frame (\d+)" % MOVED_A, t.log("a")), 10).group(1))
    w, h = rect_of(MOVED_A)["w"], rect_of(MOVED_A)["h"]
    layout = page.get("/api/layout")[2]
    if layout["canvas"] != [w, h] or layout["preview"]["size"] != [w, h] or \
            not layout["displays"] or any(d["rect"][2] > w or d["rect"][3] > h
                                          for d in layout["displays"]):
        t.fail("job a's /api/layout after its move: %r" % layout)
    preview = os.path.join(t.work, "preview-a.png")

    def preview_is_the_new_window():
        status, _, png = page.get("/api/preview.png")
        with open(preview, "wb") as f:
            f.write(png if status == 200 else b"")
        return subprocess.call([COMPARE, "--preview", t.layout, preview, ref_moved_a, MOVED_A],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) == 0
    t.wait_for("job a's preview of its new window", preview_is_the_new_window, 10)
    if page.get("/api/status")[2]["frame"] < switch_a:
        t.fail("job a's status is of a frame before its move")
    first_a = (switch_a + 9) // 10 * 10
    t.wait_for("job a's frame %d" % first_a, lambda: t.captured("a", first_a), 20)
    if subprocess.call([COMPARE, "--window", MOVED_A, t.layout, os.path.join(jobs, "a"),
                        ref_moved_a, str(first_a)]) != 0:
        t.fail("job a's frame %d (switch %d) is not the one-process render at %s" %
               (first_a, switch_a, MOVED_A))

    x, y, w, h = map(int, MOVED_B.split(","))
    forget_captures(wall_captures)
    asked = time.time()
    status, _, reply = api.send("POST", "/api/windows/2",
                                body=json.dumps({"x": x, "y": y, "w": w, "h": h}))
    if status != 200 or reply != {"id": "2", "rect": {"x": x, "y": y, "w": w, "h": h}}:
        t.fail("moving window 2: %d %r" % (status, reply))
    t.wait_for("GET /api/windows to show window 2 moved",
               lambda: rects()["2"] == {"x": x, "y": y, "w": w, "h": h}, 10)
    if rects()["1"] != rect_of(MOVED_A):
        t.fail("window 1 moved with window 2: %r" % rects())
    line = t.wait_for("job b to say it moved", lambda: re.search(
        r"the wall moved the window to %s from frame (\d+)" % MOVED_B, t.log("b")), 10)
    switch = int(line.group(1))
    # Job b captures every 10th frame: the first at or after the switch is the new window's.
    first = (switch + 9) // 10 * 10
    t.wait_for("job b's frame %d" % first, lambda: t.captured("b", first), 20)
    if subprocess.call([COMPARE, "--window", MOVED_B, t.layout, os.path.join(jobs, "b"),
                        ref_moved, str(first)]) != 0:
        t.fail("job b's frame %d (switch %d) is not the one-process render at %s" %
               (first, switch, MOVED_B))
    # The wall shows a, with b on top at its new place and size.
    t.wait_for("the wall's captures of b moved over a", lambda: composite(
        t, MOVED_A + "+" + MOVED_B, ref_moved_a + "+" + ref_moved, wall_captures), 10)
    if t.procs["b"].poll() is not None:
        t.fail("job b ended after its move")
    return ("window 1 with its page's preview at frame %d, window 2 at frame %d, the wall showed "
            "it %.2f s after the request" % (switch_a, switch, time.time() - asked))


def forget_captures(captures):
    """Removes the wall's captures so far: a wait for a new composite then reads only later ones
    (compare_captures --composite with FRAME any decodes every capture of a display)."""
    for display in os.listdir(captures):
        for name in os.listdir(os.path.join(captures, display)):
            if re.fullmatch(r"frame-\d+\.png", name):
                os.remove(os.path.join(captures, display, name))


def composite(t, windows, renders, captures):
    """Some capture of each display of the wall equals the background with the renders at their
    windows, bottom first (compare_captures --composite, FRAME any)."""
    return subprocess.call([COMPARE, "--composite", windows, t.layout, captures, renders, "any",
                            "#000000"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) == 0


if __name__ == "__main__":
    main()
