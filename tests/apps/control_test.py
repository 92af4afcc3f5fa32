#!/usr/bin/python3
"""End-to-end tests of the control API against a real running job: mpirun, render
ranks, an OSMesa wall with captures, HTTP through the standard library's urllib.

  control_test.py camera      a camera request changes what every display shows; the captures
                              before and after differ, and after equal a one-process render of
                              the new camera (--image with a one-keyframe --camera-path)
  control_test.py bad         malformed JSON, unknown fields, NaN/inf, out of range, wrong
                              types: 400 with a message each, and the wall keeps running; a POST
                              with no body and no Content-Length (curl -X POST), over a raw
                              socket, is answered at once as if the body were {}, and stops the
                              job at the end
  control_test.py token       a token always, loopback included: generated and printed as the
                              address to open; without it (or with a wrong one, or in a URL
                              other than the page's first load) 401, with it 200; the page's
                              address sets an HttpOnly SameSite=Strict cookie and redirects;
                              --control-token-file (created 0600, read again, refused when
                              others may read it) and DFBWALL_CONTROL_TOKEN, neither in the
                              log nor in ps
  control_attacks_test.py     the attacks themselves (rebinding, cross-origin, slow clients)
  control_test.py idle        converged (--max-spp): every rank uses < 5% of one core over 5 s
                              (/proc/PID/stat), and a change wakes the wall at once
Each ends the job with POST /api/stop and checks exit code 0 and complete statistics.
Needs DFBWALL, COMPARE (compare_captures) and MPIEXEC in the environment.
"""
import http.client
import json
import os
import queue
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

DFBWALL = os.environ["DFBWALL"]
COMPARE = os.environ["COMPARE"]
MPIEXEC = os.environ["MPIEXEC"]
SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
WALL = os.path.join(SOURCE, "configs", "walls", "2x2.toml")
WALL1 = os.path.join(SOURCE, "configs", "walls", "1x1.toml")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


class Job:
    """One dfbwall job under mpirun with a control server; stdout read on a thread."""

    def __init__(self, work, ranks, *args, token=None, env=None):
        """`token`: the one the job was given (a file, the environment); otherwise the one it
        prints."""
        self.work = work
        command = [MPIEXEC, "-n", str(ranks), "--oversubscribe", "--bind-to", "none", DFBWALL,
                   *args]
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                        text=True, env=env or ENV)
        self.lines = queue.Queue()
        self.log = []
        threading.Thread(target=self._read, daemon=True).start()
        self.url, self.printed_token = self._wait_for_server()
        self.token = token or self.printed_token

    def _read(self):
        for line in self.process.stdout:
            self.log.append(line)
            self.lines.put(line)

    def _wait_for_server(self):
        deadline = time.time() + 30
        while time.time() < deadline:
            try:
                line = self.lines.get(timeout=0.5)
            except queue.Empty:
                if self.process.poll() is not None:
                    self.fail("the job ended before its control server started")
                continue
            m = re.search(r"control API on (http://[^/\s]+)/(?:\?token=(\S+))?", line)
            if m:
                return m.group(1), m.group(2)
        self.fail("no 'control API on' line within 30 s")

    def fail(self, message):
        if self.process.poll() is None:
            self.process.kill()
        print("".join(self.log[-40:]))
        fail(message)

    def request(self, method, path, body=None, token="default"):
        """(status, parsed JSON body)."""
        token = self.token if token == "default" else token
        data = None if body is None else (body if isinstance(body, bytes) else
                                          json.dumps(body).encode())
        if method == "POST" and data is None:
            data = b"{}"
        req = urllib.request.Request(self.url + path, data=data, method=method)
        if token:
            req.add_header("Authorization", "Bearer " + token)
        try:
            with urllib.request.urlopen(req, timeout=10) as response:
                return response.status, json.loads(response.read())
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read() or b"{}")

    def bodiless(self, path, then=None):
        """POST `path` with no body and no Content-Length, as `curl -X POST` sends it, over a raw
        socket: (status, parsed JSON body, seconds to the answer). With `then`, a GET of that
        path follows on the same connection, whose status is returned too."""
        host, port = re.match(r"http://([^:/]+):(\d+)", self.url).groups()
        auth = "Authorization: Bearer %s\r\n" % self.token if self.token else ""
        with socket.create_connection((host, int(port)), timeout=10) as sock:
            reader = sock.makefile("rb")

            def answer():
                status = int(reader.readline().split()[1])
                length = 0
                while True:
                    line = reader.readline().strip()
                    if not line:
                        break
                    name, _, value = line.decode().partition(":")
                    if name.lower() == "content-length":
                        length = int(value)
                return status, json.loads(reader.read(length) or b"{}")

            t0 = time.time()
            sock.sendall(("POST %s HTTP/1.1\r\nHost: %s:%s\r\nUser-Agent: curl/7.88\r\n"
                          "Accept: */*\r\n%s\r\n" % (path, host, port, auth)).encode())
            status, body = answer()
            seconds = time.time() - t0
            if then is None:
                return status, body, seconds
            sock.sendall(("GET %s HTTP/1.1\r\nHost: %s:%s\r\n%s\r\n" %
                          (then, host, port, auth)).encode())
            return status, body, seconds, answer()[0]

    def status(self):
        code, body = self.request("GET", "/api/status")
        if code != 200:
            self.fail("GET /api/status gave %d: %s" % (code, body))
        return body

    def wait_for(self, what, predicate, seconds=30):
        deadline = time.time() + seconds
        while time.time() < deadline:
            s = self.status()
            if predicate(s):
                return s
            time.sleep(0.05)
        self.fail("timed out waiting for " + what + "; last status: " + json.dumps(self.status()))

    def stop(self, stats=None, bodiless=False):
        if bodiless:
            code, body, _ = self.bodiless("/api/stop")
        else:
            code, body = self.request("POST", "/api/stop")
        if code != 200 or not body.get("stopping"):
            self.fail("POST /api/stop gave %d: %s" % (code, body))
        try:
            exit_code = self.process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.fail("the job did not end within 30 s of POST /api/stop")
        if exit_code != 0:
            self.fail("the job exited with %d after POST /api/stop" % exit_code)
        if stats:
            lines = [json.loads(line) for line in open(stats)]
            ranks = [line for line in lines if "rank" in line]
            if "summary" not in lines[-1] or len(ranks) != 6:
                self.fail("statistics incomplete: %d rank lines, last line %s" % (len(ranks),
                                                                                  lines[-1]))
            summary = lines[-1]["summary"]
            if not summary["stopped_early"] or summary["exit_code"] != 0:
                self.fail("summary does not record the graceful stop: %s" % summary)
            return lines
        return None


def wall_job(work, *extra):
    return Job(work, 6, "--wall", WALL, "--offscreen", "--frames", "0", "--control",
               "127.0.0.1:0", "--quiet", *extra)


def captures(folder, display):
    return sorted(os.listdir(os.path.join(folder, display)))


def camera_scenario(work):
    cap, stats = os.path.join(work, "cap"), os.path.join(work, "stats.json")
    job = wall_job(work, "--max-spp", "2", "--spp", "1", "--seed", "7", "--max-depth", "3",
                   "--capture", cap, "--stats", stats)
    first = job.wait_for("the wall to converge", lambda s: s["idle"])
    code, body = job.request("POST", "/api/capture")
    if code != 200:
        job.fail("POST /api/capture gave %d: %s" % (code, body))
    # A capture wakes an idle wall for one frame; every display writes it.
    job.wait_for("the capture", lambda s: s["frame"] > first["frame"] and s["idle"])
    before = captures(cap, "r0c0")
    if not before:
        job.fail("no capture after POST /api/capture")
    camera = {"position": [200, 300, -600], "look_at": [300, 250, 300]}
    code, body = job.request("POST", "/api/camera", camera)
    if code != 200:
        job.fail("POST /api/camera gave %d: %s" % (code, body))
    request = body["request"]
    after = job.wait_for(
        "the new camera on every display",
        lambda s: s["last_request"]["id"] >= request and s["idle"] and
        s["presented"] >= s["frame"])
    if after["camera"]["position"] != [200.0, 300.0, -600.0]:
        job.fail("status shows camera %s" % after["camera"])
    lines = job.stop(stats)
    last = after["frame"]
    frames = [line for line in lines if "frame" in line and "request_id" in line]
    applied = [f for f in frames if f["request_id"] == request]
    if not applied or applied[0]["request_to_displays_frames"] > 3:
        job.fail("statistics of the request: %s (frames in flight 2: at most 3 frames)" % applied)
    # The one-process render of the new camera: 2 samples per pixel, as the wall converged.
    path = os.path.join(work, "path.toml")
    with open(path, "w") as f:
        f.write("[[keyframe]]\ntime = 0\nposition = [200, 300, -600]\nlook_at = [300, 250, 300]\n")
    size = subprocess.run([COMPARE, "--info", WALL], capture_output=True, text=True,
                          check=True).stdout.split()[1]
    full = os.path.join(work, "full.png")
    subprocess.run([MPIEXEC, "-n", "1", DFBWALL, "--size", size, "--image", full, "--quiet",
                    "--frames", "2", "--spp", "1", "--seed", "7", "--max-depth", "3",
                    "--camera-path", path], check=True, env=ENV)
    result = subprocess.run([COMPARE, WALL, cap, full, str(last)], capture_output=True,
                            text=True)
    if result.returncode != 0:
        fail("captures of frame %d do not equal the one-process render: %s%s" %
             (last, result.stdout, result.stderr))
    old = open(os.path.join(cap, "r0c0", before[-1]), "rb").read()
    new = open(os.path.join(cap, "r0c0", "frame-%06d.png" % last), "rb").read()
    if old == new:
        fail("the capture before the camera request equals the one after")
    print("camera request %d: frame %d on every display equals the one-process render of the "
          "new camera; %d frame(s) from request to display, %.1f ms" %
          (request, last, applied[0]["request_to_displays_frames"],
           applied[0]["request_to_displays_ms"]))


def bad_scenario(work):
    stats = os.path.join(work, "stats.json")
    job = wall_job(work, "--renderer", "pattern", "--stats", stats)
    # Before the first frame a camera request is answered 503 (try again), not checked.
    job.wait_for("the first frame", lambda s: s["frame"] >= 1)
    bad = [
        ("/api/camera", b"{not json"),
        ("/api/camera", b"[1, 2, 3]"),
        ("/api/camera", b'{"position": [1, 2, NaN]}'),
        ("/api/camera", b'{"fov": 1e999}'),
        ("/api/camera", {"zoom": 2}),
        ("/api/camera", {"fov": 500}),
        ("/api/camera", {"position": [1, 2]}),
        ("/api/camera", {"position": "here"}),
        ("/api/camera", {"dolly": 0}),
        ("/api/camera", {"up": [0, 0, 0]}),
        ("/api/camera", {"look_at": [278, 273, -800]}),  # the camera's position: unusable
        ("/api/settings", {"spp": 0}),
        ("/api/settings", {"spp": 1.5}),
        ("/api/settings", {"exposure": -1}),
        ("/api/settings", {"transfer_function": "viridis"}),  # not scivis
        ("/api/settings", {"frobnicate": True}),
        ("/api/capture", {}),  # no --capture folder
        ("/api/stop", {"now": True}),
    ]
    for path, body in bad:
        code, reply = job.request("POST", path, body)
        if code != 400 or not reply.get("error"):
            job.fail("POST %s %r gave %d %s, expected 400 with a message" % (path, body, code,
                                                                           reply))
    code, _ = job.request("GET", "/api/nothing")
    if code != 404:
        job.fail("GET /api/nothing gave %d, expected 404" % code)
    # No body and no Content-Length (curl -X POST): the body is {}, answered at once (not after
    # waiting for a body that never comes), and the connection goes on. {} itself is refused by these (no fields, no --capture folder): the
    # same answer, word for word.
    for path in ("/api/camera", "/api/settings", "/api/capture"):
        code, body, seconds, then = job.bodiless(path, then="/api/status")
        expected = job.request("POST", path, b"{}")
        if (code, body) != expected or seconds > 2 or then != 200:
            job.fail("POST %s without a body gave %d %s in %.1f s (then GET %d); with {} it gives "
                     "%d %s" % (path, code, body, seconds, then, *expected))
    code, body, _ = job.bodiless("/api/nothing")
    if code != 404:
        job.fail("POST /api/nothing without a body gave %d, expected 404" % code)
    # Still running: frames go on and a good request is applied.
    before = job.status()["frame"]
    code, body = job.request("POST", "/api/settings", {"exposure": 1.5, "spp": 2})
    if code != 200:
        job.fail("a good settings request after the bad ones gave %d: %s" % (code, body))
    request = body["request"]
    s = job.wait_for("the settings applied",
                     lambda s: s["last_request"]["id"] >= request and s["frame"] > before + 1)
    if s["settings"]["exposure"] != 1.5 or s["settings"]["spp"] != 2:
        job.fail("settings not applied: %s" % s["settings"])
    job.stop(stats, bodiless=True)
    print("%d bad requests got 400 with a message; the wall kept running and applied a good one;"
          " POSTs without a body were taken as {}, and one stopped the wall" % len(bad))


def page_address(job, token):
    """GET /?token=TOKEN without following the redirect: (status, headers)."""
    host, port = re.match(r"http://([^:/]+):(\d+)", job.url).groups()
    connection = http.client.HTTPConnection(host, int(port), timeout=10)
    connection.request("GET", "/?token=" + token)
    response = connection.getresponse()
    response.read()
    connection.close()
    return response.status, response.headers


def token_in_ps(token):
    """A process whose command line holds `token`, or None."""
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open("/proc/%s/cmdline" % pid, "rb") as f:
                if token.encode() in f.read():
                    return pid
        except OSError:
            pass
    return None


def token_scenario(work):
    pattern = ("--wall", WALL1, "--offscreen", "--frames", "0", "--renderer", "pattern",
               "--quiet")
    # Loopback, no token given: one is generated and printed as the address to open.
    job = Job(work, 2, *pattern, "--control", "127.0.0.1:0")
    if not job.printed_token or len(job.printed_token) < 32:
        job.fail("no generated token in the printed address")
    for token in (None, "wrong", job.token[:-1]):
        code, body = job.request("GET", "/api/status", token=token)
        if code != 401:
            job.fail("GET /api/status with token %r gave %d, expected 401" % (token, code))
        code, body = job.request("POST", "/api/stop", token=token)
        if code != 401:
            job.fail("POST /api/stop with token %r gave %d, expected 401" % (token, code))
    # Only the page's first load takes the token from its URL.
    code, _ = job.request("GET", "/api/status?token=" + job.token, token=None)
    if code != 401:
        job.fail("?token= on /api/status gave %d, expected 401" % code)
    code, headers = page_address(job, job.token)
    cookie = headers.get("Set-Cookie", "")
    if code != 303 or headers.get("Location") != "/" or "HttpOnly" not in cookie or \
            "SameSite=Strict" not in cookie or job.token not in cookie:
        job.fail("GET /?token= gave %d, Location %s, Set-Cookie %r" %
                 (code, headers.get("Location"), cookie))
    if page_address(job, "wrong-token-1234567890")[0] != 401:
        job.fail("GET /?token=WRONG did not give 401")
    job.status()
    job.stop()

    # --control-token-file: created 0600 with a fresh token, not printed, read again next time;
    # on every interface the printed address is loopback's.
    path = os.path.join(work, "control.token")
    job = Job(work, 2, *pattern, "--control", "0.0.0.0:0", "--control-token-file", path,
              token="unknown")
    mode = os.stat(path).st_mode & 0o777
    token = open(path).read().strip()
    if mode != 0o600 or len(token) < 32:
        job.fail("--control-token-file made mode %o with %r" % (mode, token))
    job.token = token
    if job.printed_token or token in "".join(job.log) or token_in_ps(token):
        job.fail("the token of --control-token-file shows in the log or in ps")
    if job.request("GET", "/api/status", token=None)[0] != 401:
        job.fail("a tokenless request was answered")
    job.status()
    job.stop()
    job = Job(work, 2, *pattern, "--control", "127.0.0.1:0", "--control-token-file", path,
              token=token)
    job.status()
    job.stop()

    # DFBWALL_CONTROL_TOKEN.
    secret = "env-token-0123456789abcdef"
    job = Job(work, 2, *pattern, "--control", "127.0.0.1:0", token=secret,
              env=dict(ENV, DFBWALL_CONTROL_TOKEN=secret))
    job.status()
    if job.printed_token or secret in "".join(job.log) or token_in_ps(secret):
        job.fail("DFBWALL_CONTROL_TOKEN shows in the log or in ps")
    if job.request("GET", "/api/status", token=None)[0] != 401:
        job.fail("a tokenless request was answered")
    job.stop()

    # A token file others may read is refused, naming it.
    os.chmod(path, 0o644)
    result = subprocess.run([MPIEXEC, "-n", "2", "--oversubscribe", DFBWALL, *pattern,
                             "--control", "127.0.0.1:0", "--control-token-file", path],
                            capture_output=True, text=True, env=ENV, timeout=60)
    if result.returncode == 0 or path + ": other users may read it" not in result.stderr:
        fail("a token file of mode 644 gave exit %d: %s" % (result.returncode, result.stderr))
    print("a token always: generated and printed, or from a 0600 file or the environment "
          "(neither in the log nor in ps); without it 401; the page's address sets an HttpOnly "
          "SameSite=Strict cookie and redirects to /")


def rank_pids(mpirun):
    """The ranks: mpirun's child processes."""
    with open("/proc/%d/task/%d/children" % (mpirun, mpirun)) as f:
        return [int(p) for p in f.read().split()]


def cpu_seconds(pid):
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    ticks = os.sysconf("SC_CLK_TCK")
    return (int(fields[11]) + int(fields[12])) / ticks  # utime + stime


def idle_scenario(work):
    stats = os.path.join(work, "stats.json")
    job = wall_job(work, "--renderer", "primary", "--max-spp", "3", "--stats", stats)
    job.wait_for("the wall to converge", lambda s: s["idle"])
    pids = rank_pids(job.process.pid)
    if len(pids) != 6:
        job.fail("found %d ranks under mpirun, expected 6" % len(pids))
    time.sleep(0.5)  # the last frame's acknowledgements and the renderers' threads settle
    start = {p: cpu_seconds(p) for p in pids}
    t0 = time.time()
    time.sleep(5)
    seconds = time.time() - t0
    shares = {p: (cpu_seconds(p) - start[p]) / seconds for p in pids}
    worst = max(shares.values())
    print("idle CPU per rank over %.1f s: %s (share of one core)" %
          (seconds, ", ".join("%.3f" % shares[p] for p in pids)))
    if worst >= 0.05:
        job.fail("a rank used %.1f%% of a core while the wall was idle" % (100 * worst))
    if not job.status()["idle"]:
        job.fail("the wall left idle by itself")
    # A change wakes it at once.
    t0 = time.time()
    code, body = job.request("POST", "/api/camera", {"dolly": 1.25})
    request = body["request"]
    job.wait_for("the woken wall to present the change",
                 lambda s: s["last_request"]["id"] >= request and
                 s["presented"] >= s["last_request"]["frame"], seconds=10)
    woke = time.time() - t0
    job.stop(stats)
    if woke > 3:
        fail("the change took %.1f s to reach the displays" % woke)
    print("a change after idling reached every display in %.0f ms" % (1000 * woke))


def main():
    scenarios = {"camera": camera_scenario, "bad": bad_scenario, "token": token_scenario,
                 "idle": idle_scenario}
    if len(sys.argv) != 2 or sys.argv[1] not in scenarios:
        fail("usage: control_test.py " + "|".join(scenarios))
    work = tempfile.mkdtemp()
    try:
        scenarios[sys.argv[1]](work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
