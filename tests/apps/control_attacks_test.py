#!/usr/bin/python3
"""The control API attacked as a web page or a local stranger would, against a real running job
(mpirun, a 1x1 OSMesa wall): each attack is refused and changes nothing, then a good request
still works.

  control_attacks_test.py requests   tokenless requests (401); a DNS-rebinding Host (403, with
                                     the token too); the page's cookie with a text/plain body, no
                                     Content-Type, a foreign or missing Origin (403); a CORS
                                     preflight (no Allow-Origin); the security headers on every
                                     reply. No request was applied; then the page's cookie with
                                     JSON from its own Origin changes a setting, and a bodiless
                                     POST with the Bearer token stops the job.
  control_attacks_test.py slow       50 sockets trickling a byte a second and 5 that send half a
                                     header and stop: real requests meanwhile are answered within
                                     2 s, and every slow socket is closed by the per-request
                                     deadline (5 s), however slowly its bytes come.
Needs DFBWALL, COMPARE and MPIEXEC in the environment (control_test.py's Job runs the job).
"""
import http.client
import json
import re
import select
import shutil
import socket
import sys
import tempfile
import threading
import time

from control_test import WALL1, Job, fail

SECURITY_HEADERS = {
    "Content-Security-Policy": "default-src 'self'",
    "X-Frame-Options": "DENY",
    "X-Content-Type-Options": "nosniff",
    "Cache-Control": "no-store",
    "Referrer-Policy": "no-referrer",
}


def start(work):
    return Job(work, 2, "--wall", WALL1, "--offscreen", "--frames", "0", "--renderer", "pattern",
               "--control", "127.0.0.1:0", "--quiet")


class Raw:
    """Requests with exactly the headers given (urllib adds its own)."""

    def __init__(self, job):
        self.job = job
        self.host, port = re.match(r"http://([^:/]+):(\d+)", job.url).groups()
        self.port = int(port)
        self.own = "%s:%d" % (self.host, self.port)

    def send(self, method, path, headers, body=None):
        """(status, headers, parsed body)."""
        connection = http.client.HTTPConnection(self.host, self.port, timeout=10)
        connection.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
        for name, value in headers.items():
            connection.putheader(name, value)
        if body is not None:
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

    def cookie(self):
        status, headers, _ = self.send("GET", "/?token=" + self.job.token, {"Host": self.own})
        if status != 303:
            self.job.fail("GET /?token= gave %d" % status)
        return headers["Set-Cookie"].split(";")[0]


def requests_scenario(work):
    job = start(work)
    raw = Raw(job)
    before = job.status()
    cookie = raw.cookie()
    bearer = "Bearer " + job.token
    own, origin = raw.own, "http://" + raw.own
    settings, stop = b'{"spp": 7}', b"{}"
    attacks = [
        # (what, method, path, headers, body, expected status)
        ("tokenless settings", "POST", "/api/settings",
         {"Host": own, "Content-Type": "application/json"}, settings, 401),
        ("tokenless stop", "POST", "/api/stop", {"Host": own}, None, 401),
        ("tokenless status", "GET", "/api/status", {"Host": own}, None, 401),
        ("tokenless preview", "GET", "/api/preview.png", {"Host": own}, None, 401),
        ("token in an API URL", "GET", "/api/status?token=" + job.token, {"Host": own}, None,
         401),
        ("rebinding, status", "GET", "/api/status",
         {"Host": "evil.example:%d" % raw.port, "Authorization": bearer}, None, 403),
        ("rebinding, preview with the cookie", "GET", "/api/preview.png",
         {"Host": "evil.example:%d" % raw.port, "Cookie": cookie}, None, 403),
        ("rebinding, stop", "POST", "/api/stop",
         {"Host": "evil.example:%d" % raw.port, "Authorization": bearer}, stop, 403),
        ("cookie, text/plain", "POST", "/api/settings",
         {"Host": own, "Cookie": cookie, "Content-Type": "text/plain", "Origin": origin},
         settings, 403),
        ("cookie, no Content-Type", "POST", "/api/stop",
         {"Host": own, "Cookie": cookie, "Origin": origin}, stop, 403),
        ("cookie, form-encoded", "POST", "/api/stop",
         {"Host": own, "Cookie": cookie, "Origin": origin,
          "Content-Type": "application/x-www-form-urlencoded"}, b"a=b", 403),
        ("cookie, another port's Origin", "POST", "/api/settings",
         {"Host": own, "Cookie": cookie, "Content-Type": "application/json",
          "Origin": "http://127.0.0.1:%d" % (raw.port + 1)}, settings, 403),
        ("cookie, foreign Origin", "POST", "/api/stop",
         {"Host": own, "Cookie": cookie, "Content-Type": "application/json",
          "Origin": "http://evil.example"}, stop, 403),
        ("cookie, Origin null", "POST", "/api/stop",
         {"Host": own, "Cookie": cookie, "Content-Type": "application/json", "Origin": "null"},
         stop, 403),
        ("cookie, no Origin", "POST", "/api/settings",
         {"Host": own, "Cookie": cookie, "Content-Type": "application/json"}, settings, 403),
        ("wrong cookie", "POST", "/api/settings",
         {"Host": own, "Cookie": cookie[:-1] + "x", "Content-Type": "application/json",
          "Origin": origin}, settings, 401),
    ]
    for what, method, path, headers, body, expected in attacks:
        status, reply_headers, reply = raw.send(method, path, headers, body)
        if status != expected:
            job.fail("%s: %s %s gave %d %s, expected %d" % (what, method, path, status, reply,
                                                            expected))
        for name, value in SECURITY_HEADERS.items():
            if value not in (reply_headers.get(name) or ""):
                job.fail("%s: the reply has %s: %r" % (what, name, reply_headers.get(name)))
    # A CORS preflight is never granted: no browser may send JSON from another origin.
    status, headers, _ = raw.send("OPTIONS", "/api/settings",
                                  {"Host": own, "Origin": "http://evil.example",
                                   "Access-Control-Request-Method": "POST",
                                   "Access-Control-Request-Headers": "content-type"})
    if headers.get("Access-Control-Allow-Origin") or 200 <= status < 300:
        job.fail("a preflight from evil.example gave %d, Allow-Origin %r" %
                 (status, headers.get("Access-Control-Allow-Origin")))
    after = job.status()
    if after["last_request"]["id"] != 0 or after["settings"] != before["settings"] or \
            job.process.poll() is not None:
        job.fail("an attack changed the wall: %s" % json.dumps(after))
    # The page's way: cookie, JSON, its own Origin.
    status, _, reply = raw.send("POST", "/api/settings",
                                {"Host": own, "Cookie": cookie, "Origin": origin,
                                 "Content-Type": "application/json; charset=utf-8"},
                                b'{"spp": 3}')
    if status != 200:
        job.fail("the page's settings request gave %d %s" % (status, reply))
    job.wait_for("spp 3 applied", lambda s: s["settings"]["spp"] == 3)
    # A script's way: the Bearer token, a POST without a body.
    job.stop(bodiless=True)
    print("%d attacks refused (401/403, security headers on each), nothing applied; then the "
          "page's cookie request and a bodiless Bearer stop worked" % len(attacks))


def slow_scenario(work):
    job = start(work)
    raw = Raw(job)
    job.status()
    head = ("GET /api/status HTTP/1.1\r\nHost: %s\r\nAuthorization: Bearer %s\r\n\r\n" %
            (raw.own, job.token)).encode()
    opened, closed = {}, {}
    sockets = []
    for i in range(55):
        s = socket.create_connection((raw.host, raw.port))
        s.setblocking(False)
        opened[s] = time.monotonic()
        sockets.append(s)
        if i >= 50:
            s.send(b"GET /api/status HTTP/1.1\r\nHost: 12")  # half a header, then nothing
    trickling = sockets[:50]
    done = threading.Event()

    def trickle():
        for i in range(len(head)):
            for s in trickling:
                if s not in closed:
                    try:
                        s.send(head[i:i + 1])
                    except OSError:
                        closed.setdefault(s, time.monotonic())
            if done.wait(1):
                return

    def watch():
        while not done.is_set() and len(closed) < len(sockets):
            readable, _, _ = select.select([s for s in sockets if s not in closed], [], [], 0.05)
            for s in readable:
                try:
                    if not s.recv(4096):
                        closed.setdefault(s, time.monotonic())
                except OSError:
                    closed.setdefault(s, time.monotonic())

    threads = [threading.Thread(target=trickle), threading.Thread(target=watch)]
    for t in threads:
        t.start()
    latencies = []
    try:
        end = time.monotonic() + 8
        while time.monotonic() < end:
            t0 = time.monotonic()
            code, _ = job.request("GET", "/api/status")
            latencies.append(time.monotonic() - t0)
            if code != 200:
                job.fail("a real request among the slow ones gave %d" % code)
            time.sleep(0.25)
    finally:
        deadline = time.monotonic() + 5
        while len(closed) < len(sockets) and time.monotonic() < deadline:
            time.sleep(0.1)
        done.set()
        for t in threads:
            t.join()
    open_after = [s for s in sockets if s not in closed]
    lifetimes = sorted(closed[s] - opened[s] for s in closed)
    for s in sockets:
        s.close()
    if max(latencies) > 2:
        job.fail("a real request took %.2f s among 55 slow connections" % max(latencies))
    if open_after:
        job.fail("%d slow connections still open after %.0f s" %
                 (len(open_after), time.monotonic() - min(opened.values())))
    if lifetimes[-1] > 7:
        job.fail("a slow connection lived %.1f s (deadline 5 s)" % lifetimes[-1])
    job.stop()
    print("%d real requests among 50 trickling and 5 stalled connections: slowest %.0f ms, median "
          "%.0f ms; the slow connections were closed after %.1f..%.1f s" %
          (len(latencies), 1000 * max(latencies), 1000 * sorted(latencies)[len(latencies) // 2],
           lifetimes[0], lifetimes[-1]))


def main():
    scenarios = {"requests": requests_scenario, "slow": slow_scenario}
    if len(sys.argv) != 2 or sys.argv[1] not in scenarios:
        fail("usage: control_attacks_test.py " + "|".join(scenarios))
    work = tempfile.mkdtemp()
    try:
        scenarios[sys.argv[1]](work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
