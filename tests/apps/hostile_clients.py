#!/usr/bin/python3
"""Hostile clients against a running `dfbwall serve`: the wall must survive them all, say so in
its log where it can see them, and then still run a good job byte-identically.

Usage: hostile_clients.py LAYOUT   (env DFBWALL, COMPARE, MPIEXEC as for wall_test.sh)

Which attacks the wall can see, and which ZeroMQ absorbs below our code (so nothing is logged,
and the test checks only that the connection is closed and the wall stays up):
  - a wrong token: the wall's ZAP handler refuses the PLAIN handshake (logged once per address),
    no message gets through;
  - garbage on the raw TCP port, a ZMTP frame claiming 4 GiB during the handshake, half a
    greeting then silence, half a frame then silence, connect-and-vanish, the flood of 200
    connections: libzmq's ZMTP engine drops these connections itself (bad greeting, maxmsgsize
    = 64 KiB on the directory socket, handshake_ivl / heartbeat timeout), never handing dfbwall a
    message. Not logged.
  - everything that arrives as a whole ZeroMQ message from a peer with the token is ours and is
    logged (version 7, garbage body, unknown kind, oversize text length, batches for a display
    that does not exist or a frame outside the window, busy, the job whose connection closed
    dropped at once).
"""
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

import zmq

MAGIC = 0x57424644
HELLO, DIRECTORY, REFUSED, QUEUED, KEEPALIVE, CAPTURE, BYE, PRESENTED, ENDED, BATCH = range(1, 11)
ROSTER, JOIN, WELCOME, BEAT, COMMAND, BARRIER, PIXELS, DROPPED = range(11, 19)
TOKEN = "secret"
TIMEOUT_S = 4  # serve --timeout
WATCHDOG_S = 80

layout = os.path.abspath(sys.argv[1])
dfbwall = os.environ["DFBWALL"]
compare = os.environ["COMPARE"]
mpiexec = os.environ.get("MPIEXEC") or "mpirun"
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
work = tempfile.mkdtemp(prefix="dfbwall-hostile-")
ctx = zmq.Context()
procs = []  # everything started, killed on every exit path
serve = None
stderr_path = os.path.join(work, "serve.stderr")
started = time.monotonic()


def cleanup():
    kill_all()
    for p in procs:
        p.wait()
    ctx.destroy(linger=0)


def kill_all():
    for p in procs:
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def watchdog():  # below the CTest timeout (90 s): never leave a wall behind
    print("FAIL: the test took more than %d s" % WATCHDOG_S, flush=True)
    kill_all()
    os._exit(1)


def on_signal(signum, _frame):
    kill_all()
    os._exit(128 + signum)


def fail(why):
    print("FAIL: " + why, flush=True)
    try:
        with open(stderr_path) as f:
            print("--- serve stderr ---\n" + f.read())
    except OSError:
        pass
    cleanup()
    sys.exit(1)


def start(args, **kw):
    p = subprocess.Popen(args, env=env, start_new_session=True, **kw)
    procs.append(p)
    return p


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


PROTOCOL = 4


def header(kind, session=0, version=PROTOCOL, magic=MAGIC):
    return struct.pack("<IHHQ", magic, version, kind, session)


def text(s):
    b = s.encode()
    return struct.pack("<H", len(b)) + b


def hello(token="", host="hostile", version=PROTOCOL, ranks=1):
    return (header(HELLO, 0, version) + text(token) + text(host) +
            struct.pack("<II", ranks, 64) + struct.pack("<BBBB", 0, 90, 0, 0) +
            struct.pack("<I", 2) + text("") + struct.pack("<I", 0) +
            struct.pack("<Biiii", 0, 0, 0, 0, 0) + text("") +
            struct.pack("<B", 0) +  # the window: full; no reshape
            text("") + text(""))  # no job name, no page


def parse_header(m):
    magic, version, kind, session = struct.unpack_from("<IHHQ", m)
    return kind, session


def parse_text(m, at):
    (n,) = struct.unpack_from("<H", m, at)
    return m[at + 2:at + 2 + n].decode(), at + 2 + n


def parse_directory(m):
    _, session = parse_header(m)
    at = 16 + 8
    (displays,) = struct.unpack_from("<I", m, at)
    at += 4
    owners = []
    for _ in range(displays):
        _, at = parse_text(m, at)
        owners.append(struct.unpack_from("<5i", m, at)[4])
        at += 20
    (n,) = struct.unpack_from("<I", m, at)
    at += 4
    endpoints = []
    for _ in range(n):
        e, at = parse_text(m, at)
        at += 1  # live flag
        endpoints.append(e)
    return session, owners, endpoints


def dealer(endpoint, token=TOKEN):
    """A DEALER that passes the wall's handshake (PLAIN, the token as the password)."""
    s = ctx.socket(zmq.DEALER)
    s.setsockopt(zmq.LINGER, 1000)  # a message sent just before close still goes out
    s.plain_username = b"dfbwall"
    s.plain_password = token.encode()
    s.connect(endpoint)
    return s


def ask(endpoint, message, wait_s=3.0, token=TOKEN):
    """Sends one message from a fresh DEALER; the reply or None. Returns (socket, reply)."""
    s = dealer(endpoint, token)
    try:  # never blocks: a refused peer's pipe may be gone already, and no peer would come
        s.send(message, zmq.NOBLOCK)
    except zmq.Again:
        pass
    if s.poll(int(wait_s * 1000)):
        return s, s.recv()
    return s, None


def log_text():
    with open(stderr_path, errors="replace") as f:
        return f.read()


def wait_log(needle, seconds):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if needle in log_text():
            return True
        if serve.poll() is not None:
            fail("serve exited (%s) while waiting for %r" % (serve.returncode, needle))
        time.sleep(0.1)
    return False


def expect_log(case, needle, seconds=5):
    if not wait_log(needle, seconds):
        fail("%s: no log line containing %r" % (case, needle))
    line = next(l for l in log_text().splitlines() if needle in l)
    print("%s: %s" % (case, line), flush=True)


def alive(case):
    if serve.poll() is not None:
        fail("the wall exited (%s) after %s" % (serve.returncode, case))


def raw(port):
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    return s


def closed_by_peer(s, seconds):
    """True once the wall closed the raw connection (EOF or reset) within `seconds`."""
    s.settimeout(0.2)
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            if s.recv(65536) == b"":
                return True
        except socket.timeout:
            continue
        except OSError:
            return True
    return False


# A ZMTP 3.1 greeting of a PLAIN client: the wall's sockets go on to the handshake, where the
# client's HELLO command would come next.
GREETING = (b"\xff" + b"\x00" * 8 + b"\x7f" + b"\x03\x01" + b"PLAIN".ljust(20, b"\x00") +
            b"\x00" + b"\x00" * 31)


def zmtp_handshake(port):
    s = raw(port)
    s.sendall(GREETING)
    return s


def good_session(who):
    """Hello with the good token until the wall is idle again; (socket, session, owners, endpoints)."""
    deadline = time.monotonic() + 3 * TIMEOUT_S + 10
    while time.monotonic() < deadline:
        s, reply = ask(endpoint, hello(host=who))
        if reply is not None and parse_header(reply)[0] == DIRECTORY:
            return (s,) + parse_directory(reply)
        s.close()
        time.sleep(0.3)
    fail(who + ": the wall never took a job with the good token")


def batch(session, frame, display, rank=0):
    piece = struct.pack("<4iI", 0, 0, 4, 4, 64) + b"\x80" * 64
    return header(BATCH, session) + struct.pack("<IiIII", frame, display, rank, 0, 1) + piece


def wait_ended(s, case):
    if not s.poll(int((TIMEOUT_S + 6) * 1000)):
        fail(case + ": the wall never told the job it ended")
    kind, _ = parse_header(s.recv())
    if kind != ENDED:
        fail("%s: expected Ended, got kind %d" % (case, kind))


watch = threading.Timer(WATCHDOG_S, watchdog)
watch.daemon = True
watch.start()
for signum in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
    signal.signal(signum, on_signal)
try:
    port = free_port()
    endpoint = "tcp://127.0.0.1:%d" % port
    with open(stderr_path, "w") as err:
        serve = start([mpiexec, "--oversubscribe", "--bind-to", "none", "-np", "4", dfbwall, "serve", "--wall", layout,
                       "--listen", "127.0.0.1:%d" % port, "--offscreen", "--max-jobs", "1", "--timeout",
                       str(TIMEOUT_S), "--token", TOKEN, "--capture-root", work],
                      stdout=subprocess.PIPE, stderr=err, text=True)
    # The "wall service on" line, read in a thread so a silent serve cannot hang the test.
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(iter(serve.stdout.readline, "")),
                              daemon=True)
    reader.start()
    deadline = time.monotonic() + 30
    while not any("dfbwall: wall service on" in l for l in lines):
        if serve.poll() is not None or time.monotonic() > deadline:
            fail("serve did not come up: %r" % lines)
        time.sleep(0.1)
    print("up: " + next(l for l in lines if "wall service on" in l).strip(), flush=True)

    # (a) a hello with a wrong token: refused at the handshake (no reply: the hello never
    # arrives), and logged.
    s, reply = ask(endpoint, hello(host="hostile-a"), 2.0, token="wrong")
    if reply is not None:
        fail("(a) wrong token: the wall answered %r" % reply)
    s.close()
    expect_log("(a) wrong token", "refused a connection from 127.0.0.1 at the handshake: not the "
               "wall's token")

    # (b) garbage bytes on the raw TCP port: zmq's greeting check drops the connection (not
    # ours to log); garbage as a whole zmq message is ours and logged.
    g = raw(port)
    g.sendall(b"GET / HTTP/1.1\r\nHost: wall\r\n\r\n" + os.urandom(512))
    if not closed_by_peer(g, 10):
        fail("(b) garbage on raw TCP: the connection stayed open")
    g.close()
    print("(b) raw garbage: connection closed by zmq (silently, below our logging)")
    s, _ = ask(endpoint, b"\x00garbage, not a dfbwall message at all", 0.2)
    s.close()
    expect_log("(b) garbage message", "ignored a message on the directory port: not the dfbwall "
               "protocol (wrong magic number)")
    alive("garbage")

    # (c) a hello in protocol version 7: logged (the wall sends no reply to a version it does
    # not speak; the job times out on its side).
    s, reply = ask(endpoint, hello(version=7, host="hostile-c"), 0.5)
    s.close()
    expect_log("(c) version 7", "protocol version 7, this side speaks %d" % PROTOCOL)

    # (d) sizes that lie. (d1) raw ZMTP: a valid greeting, then a frame whose 64-bit length says
    # 4 GiB: libzmq refuses it against maxmsgsize (64 KiB here) before allocating and drops the
    # connection; dfbwall never sees it, so nothing is logged. (d2) a whole zmq
    # message (a hello) whose text length says 65535 bytes: ours, refused and logged.
    d = zmtp_handshake(port)
    d.sendall(b"\x02" + struct.pack(">Q", 4 << 30) + b"\x00" * 4096)
    if not closed_by_peer(d, 10):
        fail("(d) a 4 GiB frame: the connection stayed open")
    d.close()
    print("(d1) 4 GiB ZMTP frame: connection closed by zmq (maxmsgsize; silently)")
    s, reply = ask(endpoint, header(HELLO) + struct.pack("<H", 0xFFFF) + b"x" * 32)
    if reply is None or parse_header(reply)[0] != REFUSED:
        fail("(d2) a hello with a 64 KiB text length: no Refused reply")
    s.close()
    expect_log("(d2) oversize text length", "refused a job: malformed hello: a text field longer")
    alive("sizes that lie")

    # (j) a message on the directory port of an unknown kind, and a known kind outside a job.
    s, _ = ask(endpoint, header(42) + b"\x00" * 16, 0.2)
    s.close()
    expect_log("(j) unknown kind", "ignored a message on the directory port: unknown message kind 42")
    s, _ = ask(endpoint, header(CAPTURE, 12345) + b"\x00" * 16, 0.2)
    s.close()
    expect_log("(j) kind outside a job", "message kind 6 outside a job")

    # (k) strangers with the token posing as wall processes: as the head (process 0), as a
    # process the layout does not have, with another layout; a barrier and a beat from a link
    # that never joined. Each refused (or told it is not in the wall), logged, and the wall goes
    # on. (Without the token nothing gets past the handshake: (a).)
    def join(token="", process=1, layout_hash=0):
        return (header(JOIN) + text(token) + struct.pack("<I", process) + text("hostile-k") +
                text("tcp://127.0.0.1:9") + struct.pack("<QQ", layout_hash, 1))
    for case, message, needle in [
            ("as the head", join(process=0), b"is the head"),
            ("process 99", join(process=99), b"is not one of them"),
            ("another layout", join(layout_hash=12345), b"layout is not the wall's")]:
        s, reply = ask(endpoint, message)
        if reply is None or parse_header(reply)[0] != REFUSED or needle not in reply:
            fail("(k) join %s: expected a Refused reply naming %r, got %r" % (case, needle, reply))
        s.close()
    expect_log("(k) join as the head", "refused wall process 0 from hostile-k")
    for case, message in [("barrier", header(BARRIER, 5) + struct.pack("<IIq", 1, 1, 0)),
                          ("beat", header(BEAT) + struct.pack("<Qq", 1, 0))]:
        s, reply = ask(endpoint, message)
        if reply is None or parse_header(reply)[0] != DROPPED:
            fail("(k) a %s from a stranger: expected Dropped, got %r" % (case, reply))
        s.close()
    alive("strangers posing as wall processes")

    # (e) a batch for a display that does not exist, with a real session's id (this breaks that
    # session: the wall must drop the job and survive). Also garbage on the piece port first.
    js, session, owners, endpoints = good_session("hostile-e")
    p, _ = ask(endpoints[1], b"garbage on the piece port", 0.2)
    p.close()
    expect_log("(e) piece-port garbage", "dropped a message on the piece port from connection")
    p = dealer(endpoints[0])
    p.send(batch(session, 1, 99))
    wait_ended(js, "(e)")
    p.close()
    js.close()
    expect_log("(e) display 99", "dropping the job from hostile-e: render rank 0 sent a piece of "
               "display 99, which wall process 0 does not drive")
    alive("(e)")

    # (f) a batch for a frame far outside the window.
    js, session, owners, endpoints = good_session("hostile-f")
    p = dealer(endpoints[owners[0]])
    p.send(batch(session, 1000000, 0))
    wait_ended(js, "(f)")
    p.close()
    js.close()
    expect_log("(f) frame outside the window", "dropping the job from hostile-f: render rank 0 "
               "sent a piece for frame 1000000, more than")
    alive("(f)")

    # (g) half a message then silence: half a greeting, and half a frame after the greeting.
    # libzmq's handshake_ivl (--timeout, at most 10 s) closes both; not logged.
    g1 = raw(port)
    g1.sendall(GREETING[:30])
    g2 = zmtp_handshake(port)
    g2.sendall(b"\x00\x40" + header(HELLO)[:10])  # says 64 bytes, sends 10

    # (h) connect-and-vanish: raw TCP, a zmq DEALER, and a job that said hello and vanished
    # (while it holds the wall a second job is refused as busy; once its connection closes the
    # wall drops it at once, within half its --timeout).
    for _ in range(5):
        raw(port).close()
    dealer(endpoint).close()
    vanished, session, _, _ = good_session("hostile-h")
    s, reply = ask(endpoint, hello(host="hostile-busy"))
    if reply is None or parse_header(reply)[0] != REFUSED or b"busy" not in reply:
        fail("(h) busy: expected a Refused 'busy' reply, got %r" % reply)
    s.close()
    expect_log("(h) busy", "refused a job from hostile-busy: busy")
    vanished.close()
    expect_log("(h) vanished job", "dropping the job from hostile-h: its connection closed",
               TIMEOUT_S / 2)

    # (i) a flood of 200 connections at once, half of them saying garbage, then all gone.
    flood = []
    for i in range(200):
        c = socket.socket()
        c.settimeout(5)
        c.connect(("127.0.0.1", port))
        if i % 2:
            c.sendall(os.urandom(64))
        flood.append(c)
    for c in flood:
        c.close()
    alive("(i) flood")
    print("(i) flood of 200 connections: absorbed by zmq, wall alive")

    print("(h) connect-and-vanish (raw, DEALER): absorbed by zmq silently")
    for name, c in (("half a greeting", g1), ("half a frame", g2)):
        if not closed_by_peer(c, 2 * TIMEOUT_S + 4):
            fail("(g) %s then silence: the wall never closed the connection" % name)
        c.close()
        print("(g) %s then silence: connection closed by zmq (silently)" % name)
    alive("all hostile clients")

    # The good job, after all that.
    capture = os.path.join(work, "capture")
    job = start([mpiexec, "--bind-to", "none", "-np", "2", dfbwall, "--connect", "127.0.0.1:%d" % port, "--token",
                 TOKEN, "--renderer", "pattern", "--frames", "3", "--capture", capture, "--quiet",
                 "--timeout", "20"])
    try:
        rc = job.wait(timeout=60)
    except subprocess.TimeoutExpired:
        fail("the good job hung")
    if rc != 0:
        fail("the good job exited %d" % rc)
    names = sorted(n for n in os.listdir(capture) if os.path.isdir(os.path.join(capture, n)))
    if len(names) != 4 or not all(os.listdir(os.path.join(capture, n)) for n in names):
        fail("expected captures of 4 displays, got %s" % sorted(os.listdir(capture)))
    full = os.path.join(work, "full.png")
    size = subprocess.run([compare, "--info", layout], capture_output=True, text=True,
                          env=env).stdout.split()[1]  # the canvas, 412x310 for 2x2.toml
    single = start([mpiexec, "--bind-to", "none", "-np", "1", dfbwall, "--renderer", "pattern",
                    "--frames", "3", "--size", size, "--image", full, "--quiet"])
    if single.wait(timeout=60) != 0:
        fail("the single renderer failed")
    cmp = subprocess.run([compare, layout, capture, full, "3"], env=env)
    if cmp.returncode != 0:
        fail("the good job's captures differ from one renderer")
    print("good job: exit 0, captures %s byte-identical to one renderer" % names, flush=True)

    # Stop the wall: SIGUSR1 to mpirun, exit 0 within 10 s.
    serve.send_signal(signal.SIGUSR1)
    try:
        rc = serve.wait(timeout=10)
    except subprocess.TimeoutExpired:
        fail("serve did not stop within 10 s of SIGUSR1")
    if rc != 0:
        fail("serve exited %d after SIGUSR1" % rc)
    print("serve stopped with exit 0; %.1f s in all" % (time.monotonic() - started), flush=True)
    cleanup()
    shutil.rmtree(work, ignore_errors=True)
except SystemExit:
    raise
except BaseException as e:  # any other error, Ctrl-C included: nothing left running
    import traceback
    traceback.print_exc()
    fail("%s: %s" % (type(e).__name__, e))
