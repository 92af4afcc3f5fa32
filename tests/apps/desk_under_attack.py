#!/usr/bin/python3
"""One bad job, member or flood cannot wedge a serving wall (docs/security.md, "One bad job,
member or flood cannot wedge the wall"). Four attacks, each followed by the wall still serving:

  1. flood: a 2-process wall (mpirun -np 2 serve) renders a good job (frames 0, a capture of
     every frame) while raw ZeroMQ clients flood the head's directory port with garbage, wrong-token
     hellos and strangers' beats from ever new connections: every display keeps presenting new
     frames every second and no wall process is dropped.
  2. captures: a job (a raw client that said hello with the token) asks for more captures than
     the wall keeps and for a frame far ahead: the excess is refused with a message naming the
     bound, with its session (the job goes on), and a good job still runs after it.
  3. a member that beats but never arrives: the head alone (`serve --process 0`), and a raw client
     that joins as process 1 with the token and the layout's hash, answers Start, beats, and
     never comes to a swap barrier. The head drops it within the timeout; a good job's frames go
     on on the head's display and the job ends with exit 0. While the job runs the member also
     sends input events the head must drop: one on the head's display (not the member's) and one
     that is no event; the head logs both and the job never hears of them.
  4. a bad Start: a raw client as the head, `serve --process 1 --join` to it; a Start with tile
     size 0 is refused (Ready 0, naming the field), the process does not crash and still stops
     cleanly on the head's Shutdown.

Usage: desk_under_attack.py   (env DFBWALL, MPIEXEC). The wall takes `--token` today; when it
reads its token elsewhere, only `serve_args` and `TOKEN` change. Prints what it measured.
"""
import os
import random
import re
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
import zmq.auth.thread

MAGIC = 0x57424644
PROTOCOL = 4
HELLO, DIRECTORY, REFUSED, QUEUED, KEEPALIVE, CAPTURE, BYE, PRESENTED, ENDED, BATCH = range(1, 11)
ROSTER, JOIN, WELCOME, BEAT, COMMAND, BARRIER, PIXELS, DROPPED = range(11, 19)
CMD_START, CMD_SHUTDOWN, CMD_READY, CMD_INPUT = 1, 7, 8, 16
INPUT = 20  # the wall -> job message kind of an input event
TOKEN = "desk-secret"
TIMEOUT_S = 2  # serve --timeout
WATCHDOG_S = 170

dfbwall = os.environ["DFBWALL"]
mpiexec = os.environ.get("MPIEXEC") or "mpirun"
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
work = tempfile.mkdtemp(prefix="dfbwall-desk-")
layout = os.path.join(work, "2x1.toml")
with open(layout, "w") as f:
    f.write("[grid]\ncolumns = 2\nrows = 1\ndisplay_size = [96, 64]\n")
ctx = zmq.Context()
authenticator = None  # the fake wall sockets' ZAP handler, started by plain_server()
stoppers = []  # what cleanup() stops before the context goes (threads that use its sockets)
procs = []
logs = []  # (name, path) shown on failure
started = time.monotonic()


def kill_all():
    for p in procs:
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def cleanup():
    kill_all()
    for p in procs:
        p.wait()
    for stop in stoppers:
        stop()
    if authenticator is not None:
        authenticator.stop()
    ctx.destroy(linger=0)


def fail(why):
    print("FAIL: " + why, flush=True)
    for name, path in logs:
        try:
            with open(path, errors="replace") as f:
                print("--- %s (last 30 lines) ---\n%s" % (name, "".join(f.readlines()[-30:])))
        except OSError:
            pass
    cleanup()
    sys.exit(1)


def watchdog():
    print("FAIL: the test took more than %d s" % WATCHDOG_S, flush=True)
    kill_all()
    os._exit(1)


def start(name, args):
    path = os.path.join(work, name + ".log")
    out = open(path, "w")
    p = subprocess.Popen(args, env=env, start_new_session=True, stdout=out,
                         stderr=subprocess.STDOUT, text=True)
    procs.append(p)
    logs.append((name, path))
    return p, path


def read(path):
    with open(path, errors="replace") as f:
        return f.read()


def wait_for(what, check, seconds):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if check():
            return time.monotonic()
        time.sleep(0.05)
    fail("no %s within %s s" % (what, seconds))


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


# ---- the wire protocol (wall/service/protocol/), as an attacker writes it ----

def header(kind, session=0):
    return struct.pack("<IHHQ", MAGIC, PROTOCOL, kind, session)


def text(s):
    b = s.encode()
    return struct.pack("<H", len(b)) + b


def control(kind, session, value, second=0):
    return header(kind, session) + struct.pack("<Qq", value, second)


def hello(token=TOKEN, host="attacker"):
    return (header(HELLO) + text(token) + text(host) + struct.pack("<II", 1, 64) +
            struct.pack("<BBBB", 0, 90, 0, 0) + struct.pack("<I", 2) + text("") +
            struct.pack("<I", 0) + struct.pack("<Biiii", 0, 0, 0, 0, 0) + text("") +
            struct.pack("<B", 0) + text("") + text(""))


def kind_of(m):
    return struct.unpack_from("<IHHQ", m)[2]


def session_of(m):
    return struct.unpack_from("<IHHQ", m)[3]


def text_of(m):
    (n,) = struct.unpack_from("<H", m, 16)
    return m[18:18 + n].decode(errors="replace")


def directory_layout(m):
    """(session, canvas, displays as (name, x0, y0, x1, y1, process), process count)."""
    at = 16
    width, height, count = struct.unpack_from("<iiI", m, at)
    at += 12
    displays = []
    for _ in range(count):
        (n,) = struct.unpack_from("<H", m, at)
        name = m[at + 2:at + 2 + n]
        at += 2 + n
        displays.append((name,) + struct.unpack_from("<5i", m, at))
        at += 20
    (processes,) = struct.unpack_from("<I", m, at)
    return session_of(m), (width, height), displays, processes


def layout_hash(canvas, displays, processes):
    """wall/service/protocol/LinkMessages.cpp layoutHash: FNV-1a over canvas and displays."""
    h = 0xcbf29ce484222325

    def mix(b):
        nonlocal h
        for byte in b:
            h = ((h ^ byte) * 0x100000001b3) & 0xffffffffffffffff
    mix(struct.pack("<3i", canvas[0], canvas[1], processes))
    for name, *fields in displays:
        mix(name + b"\x00")
        mix(struct.pack("<5i", *fields))
    return h


# CommandHeader (wall/service/protocol/ServiceCommands.h): kind, process, session, a, b,
# pieceSession, tileSize, renderRanks, framesInFlight, captureEvery, codec, the window (x0, y0,
# x1, y1), textBytes.
COMMAND_HEADER = "<IiQqqQ5I4iI"


def command(kind, session, a=0, tile=64, ranks=1, in_flight=2, text_=b""):
    body = struct.pack(COMMAND_HEADER, kind, 0, session, a, 0, 0, tile, ranks, in_flight, 0, 0,
                       0, 0, 0, 0, len(text_)) + text_
    return header(COMMAND, session) + body


def parse_command(m):
    fields = struct.unpack_from(COMMAND_HEADER, m, 16)
    size = struct.calcsize(COMMAND_HEADER)
    return fields, m[16 + size:16 + size + fields[-1]].decode(errors="replace")


def join(process, endpoint, hash_, incarnation):
    return (header(JOIN) + text(TOKEN) + struct.pack("<I", process) + text("fake-member") +
            text(endpoint) + struct.pack("<QQ", hash_, incarnation))


def dealer(endpoint):
    """A DEALER that passes the wall's handshake (PLAIN, the token as the password)."""
    s = ctx.socket(zmq.DEALER)
    s.setsockopt(zmq.LINGER, 0)
    s.plain_username = b"dfbwall"
    s.plain_password = TOKEN.encode()
    s.connect(endpoint)
    return s


def plain_server(s):
    """Makes s take the wall processes' handshake (PLAIN, the token as the password). libzmq
    fails a PLAIN handshake when no ZAP handler answers, so one is started for the context."""
    global authenticator
    if authenticator is None:
        authenticator = zmq.auth.thread.ThreadAuthenticator(ctx)
        authenticator.start()
        authenticator.configure_plain(domain="*", passwords={"dfbwall": TOKEN})
    s.plain_server = True


def recv_kind(s, kinds, seconds):
    """The next message of one of `kinds` within `seconds` (others skipped), or None."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if s.poll(50):
            m = s.recv()
            if kind_of(m) in kinds:
                return m
    return None


def serve_args(extra):
    return [dfbwall, "serve", "--wall", layout, "--offscreen", "--timeout", str(TIMEOUT_S),
            "--token", TOKEN, "--capture-root", work] + extra


def start_serve(name, launcher, extra):
    p, path = start(name, launcher + serve_args(extra))
    wait_for(name + " up", lambda: "wall service on" in read(path) or p.poll() is not None, 30)
    if p.poll() is not None:
        fail(name + " exited %s" % p.returncode)
    return p, path


def job_args(port, frames, capture_dir, extra=()):
    return ([mpiexec, "--oversubscribe", "--bind-to", "none", "-np", "1", dfbwall,
             "--connect", "127.0.0.1:%d" % port, "--token", TOKEN, "--renderer", "pattern",
             "--frames", str(frames), "--quiet", "--timeout", "20", "--capture", capture_dir]
            + list(extra))


def latest(capture_dir, display):
    try:
        names = os.listdir(os.path.join(capture_dir, display))
    except OSError:
        return 0
    frames = [int(m.group(1)) for m in map(re.compile(r"^frame-(\d+)\.png$").match, names) if m]
    return max(frames, default=0)


def stop_serve(p, name):
    p.send_signal(signal.SIGUSR1) if p.args[0] == mpiexec else p.send_signal(signal.SIGTERM)
    try:
        p.wait(timeout=15)
    except subprocess.TimeoutExpired:
        fail(name + " did not stop within 15 s")


def good_job(port, name, frames=3):
    cap = os.path.join(work, name + "-cap")
    job, path = start(name, job_args(port, frames, cap))
    try:
        rc = job.wait(timeout=60)
    except subprocess.TimeoutExpired:
        fail(name + " hung")
    if rc != 0:
        fail("%s exited %d" % (name, rc))
    return cap


# ---- 1. a flood of garbage while a good job renders on a 2-process wall ----

def flood(endpoint, seconds, counts):
    """Garbage of every kind as fast as one thread sends, from a pool of connections of which one
    is replaced by a new one every 500 messages (a banned connection's successor starts over)."""
    rnd = random.Random(7)
    deadline = time.monotonic() + seconds
    kinds = [
        lambda: os.urandom(rnd.randint(1, 40)),                            # not our protocol
        lambda: header(JOIN) + os.urandom(8),                               # malformed join
        lambda: header(42) + b"\0" * 16,                                    # unknown kind
        lambda: hello(token="guess", host="flood\n\x1b[31mred"),            # wrong token
        lambda: control(BEAT, 0, 1),                                        # a stranger's beat
        lambda: control(CAPTURE, 99, 1, 1),                                 # outside a job
    ]

    def connection():
        s = dealer(endpoint)
        s.setsockopt(zmq.SNDHWM, 10000)
        counts[1] += 1
        return s
    pool = [connection() for _ in range(32)]
    sent = 0
    while time.monotonic() < deadline:
        s = rnd.choice(pool)
        try:
            s.send(rnd.choice(kinds)(), zmq.NOBLOCK)
            counts[0] += 1
        except zmq.Again:
            pass
        while s.poll(0):  # what the wall answers is read and dropped
            s.recv()
        sent += 1
        if sent % 500 == 0:
            at = rnd.randrange(len(pool))
            pool[at].close()
            pool[at] = connection()
    for s in pool:
        s.close()


def attack_flood():
    port = free_port()
    endpoint = "tcp://127.0.0.1:%d" % port
    serve, serve_log = start_serve("flood-serve", [mpiexec, "--oversubscribe", "--bind-to",
                                                   "none", "-np", "2"],
                                   ["--listen", "127.0.0.1:%d" % port])
    cap = os.path.join(work, "flood-cap")
    job, job_log = start("flood-job", job_args(port, 0, cap, ["--capture-every", "1"]))
    wait_for("frames of the good job", lambda: latest(cap, "r0c0") > 5 and
             latest(cap, "r0c1") > 5, 30)
    quiet = (latest(cap, "r0c0"), time.monotonic())
    time.sleep(3)
    before = (latest(cap, "r0c0"), time.monotonic())
    quiet_fps = (before[0] - quiet[0]) / (before[1] - quiet[1])
    counts = [0, 0]
    seconds = 8
    threads = [threading.Thread(target=flood, args=(endpoint, seconds, counts)) for _ in range(2)]
    for t in threads:
        t.start()
    # Every second of the flood, both displays present new frames.
    t0 = time.monotonic()
    seen = {d: latest(cap, d) for d in ("r0c0", "r0c1")}
    stalls = []
    while time.monotonic() - t0 < seconds:
        time.sleep(1.0)
        for d in seen:
            now = latest(cap, d)
            if now <= seen[d]:
                stalls.append("%s at %.1f s" % (d, time.monotonic() - t0))
            seen[d] = now
    for t in threads:
        t.join()
    after = (latest(cap, "r0c0"), time.monotonic())
    if stalls:
        fail("frames stopped during the flood: " + ", ".join(stalls))
    if "lost wall process" in read(serve_log):
        fail("a wall process was dropped during the flood")
    if job.poll() is not None:
        fail("the good job ended during the flood (exit %s)" % job.returncode)
    fps = (after[0] - before[0]) / (after[1] - before[1])
    print("1. flood: %d garbage messages on %d connections in %d s (%.0f/s); the good job "
          "presented %d frames meanwhile (%.1f frames/s; %.1f before the flood), no display "
          "stalled for 1 s, no process dropped" % (counts[0], counts[1], seconds,
                                                    counts[0] / seconds, after[0] - before[0],
                                                    fps, quiet_fps), flush=True)
    log = read(serve_log)
    if "flood\n" in log or "\x1b" in log:
        fail("a peer's host name reached the log unescaped")
    job.send_signal(signal.SIGTERM)
    try:
        job.wait(timeout=20)
    except subprocess.TimeoutExpired:
        fail("the flooded job did not stop on SIGTERM")
    return serve, port


# ---- 2. more captures than the wall keeps, and a frame far ahead ----

def attack_captures(serve, port):
    endpoint = "tcp://127.0.0.1:%d" % port
    s = None
    deadline = time.monotonic() + 3 * TIMEOUT_S + 10
    while time.monotonic() < deadline:  # the wall may still be ending the flooded job
        s = dealer(endpoint)
        s.send(hello(host="capture-attacker"))
        reply = recv_kind(s, (DIRECTORY, REFUSED), 3)
        if reply is not None and kind_of(reply) == DIRECTORY:
            break
        s.close()
        s = None
        time.sleep(0.3)
    if s is None:
        fail("2. the wall never took the capture attacker's job")
    session = session_of(reply)
    for sequence in range(1, 21):
        s.send(control(CAPTURE, session, 1, sequence))
    s.send(control(CAPTURE, session, 1 << 40, 21))
    refused = []
    deadline = time.monotonic() + 2
    while time.monotonic() < deadline:
        s.send(control(KEEPALIVE, session, 0))  # the job is alive, it just renders nothing
        m = recv_kind(s, (REFUSED, ENDED), 0.3)
        if m is None:
            continue
        if kind_of(m) == ENDED:
            fail("2. the wall ended the job for asking too many captures: " + text_of(m))
        if session_of(m) != session:
            fail("2. a refused capture without the job's session")
        refused.append(text_of(m))
    many = [r for r in refused if "8 captures wait for their frames already" in r]
    far = [r for r in refused if "is not near the frames in flight" in r]
    if len(many) != 12 or len(far) != 1:
        fail("2. expected 12 captures over the bound and 1 far frame refused, got %r" % refused)
    s.send(control(BYE, session, 0))
    s.close()
    print("2. captures: 20 asked, 8 kept, 12 refused ('%s'), frame 2^40 refused ('%s')" %
          (many[0], far[0]), flush=True)
    good_job(port, "after-captures")
    print("   a good job after it: exit 0", flush=True)
    stop_serve(serve, "flood-serve")
    if serve.returncode != 0:
        fail("the 2-process wall exited %d on SIGUSR1" % serve.returncode)


# ---- 3. a member that beats but never comes to a barrier ----

def attack_member_that_never_arrives():
    port = free_port()
    endpoint = "tcp://127.0.0.1:%d" % port
    serve, serve_log = start_serve("head-serve", [],
                                   ["--process", "0", "--listen", "127.0.0.1:%d" % port])
    # The layout's hash, as every process computes it, from the directory a hello gets.
    s = dealer(endpoint)
    s.send(hello(host="layout-reader"))
    d = recv_kind(s, (DIRECTORY,), 10)
    if d is None:
        fail("3. no directory for the layout reader")
    session, canvas, displays, processes = directory_layout(d)
    s.send(control(BYE, session, 0))
    s.close()
    hash_ = layout_hash(canvas, displays, processes)
    # Its piece socket takes the job's pieces and drops them.
    pieces = ctx.socket(zmq.ROUTER)
    pieces.setsockopt(zmq.LINGER, 0)
    plain_server(pieces)
    piece_port = pieces.bind_to_random_port("tcp://127.0.0.1")
    member = dealer(endpoint)
    incarnation = 424242
    stop = threading.Event()
    events = {}

    def fake_member():
        joined = False
        last_beat = 0
        while not stop.is_set():
            now = time.monotonic()
            if not joined and now - last_beat > 0.5:
                member.send(join(1, "tcp://127.0.0.1:%d" % piece_port, hash_, incarnation))
                last_beat = now
            if joined and now - last_beat > TIMEOUT_S / 4:
                member.send(control(BEAT, 0, incarnation))
                last_beat = now
            while pieces.poll(0):
                pieces.recv_multipart()
                events.setdefault("pieces", time.monotonic())
            if "pieces" in events and "start" in events and "inputs" not in events:
                # The job runs: a key at (10, 10), on the head's display, and bytes that are no
                # input event, both for the job's session.
                session = events["session"]
                key = header(INPUT, session) + struct.pack("<IIiiiiB", 1, 1, 10, 10, 0, 0, 0)
                member.send(command(CMD_INPUT, session, text_=key))
                member.send(command(CMD_INPUT, session, text_=b"no input event"))
                events["inputs"] = time.monotonic()
            if not member.poll(20):
                continue
            m = member.recv()
            kind = kind_of(m)
            if kind == WELCOME:
                joined = True
                events.setdefault("joined", time.monotonic())
            elif kind == COMMAND:
                fields, _ = parse_command(m)
                if fields[0] == CMD_START:
                    answer = struct.pack(COMMAND_HEADER, CMD_READY, 1, fields[2], 1, 0, 0, 0, 0,
                                         0, 0, 0, 0, 0, 0, 0, 0)
                    member.send(header(COMMAND, fields[2]) + answer)
                    events.setdefault("session", fields[2])
                    events.setdefault("start", time.monotonic())
            elif kind == DROPPED:
                events.setdefault("dropped", time.monotonic())

    t = threading.Thread(target=fake_member)

    def stop_member():  # before its sockets close, by the finally below or by fail()
        stop.set()
        t.join()
    stoppers.append(stop_member)
    t.start()
    try:
        wait_for("the fake member's welcome", lambda: "joined" in events, 10)
        cap = os.path.join(work, "member-cap")
        job, job_log = start("member-job", job_args(port, 60, cap, ["--capture-every", "1"]))
        wait_for("the Start at the fake member", lambda: "start" in events, 20)
        lost = wait_for("the head dropping the member",
                        lambda: "lost wall process 1" in read(serve_log), TIMEOUT_S + 8)
        line = next(l for l in read(serve_log).splitlines() if "lost wall process 1" in l)
        if "did not come to the swap barrier" not in line:
            fail("3. the member was dropped, but not for the barrier: " + line)
        after = lost - events["start"]
        try:
            rc = job.wait(timeout=60)
        except subprocess.TimeoutExpired:
            fail("3. the job hung after the member was dropped")
        if rc != 0:
            fail("3. the job exited %d after the member was dropped" % rc)
        frames = latest(cap, "r0c0")
        if frames != 60:
            fail("3. the head's display presented up to frame %d of 60" % frames)
        if "pieces" not in events:
            fail("3. the fake member's piece socket got no pieces (its handshake failed?)")
        if "inputs" not in events:
            fail("3. the fake member sent no input events")
        for why in ("wall process 1 sent an input event at 10,10, outside the job's window on its "
                    "displays", "wall process 1 sent a malformed input event"):
            if why not in read(serve_log):
                fail("3. the head did not drop an input event: no '%s'" % why)
        print("3. a member that beats but never arrives: dropped %.1f s after its Start "
              "(timeout %d s): '%s'; the job's 60 frames presented on the head's display, exit 0; "
              "its hostile input events dropped"
              % (after, TIMEOUT_S, line.strip()), flush=True)
    finally:
        stop_member()
        stoppers.remove(stop_member)
        member.close()
        pieces.close()
    stop_serve(serve, "head-serve")


# ---- 4. a Start with tile size 0 to a member ----

def attack_bad_start():
    head = ctx.socket(zmq.ROUTER)
    head.setsockopt(zmq.LINGER, 0)
    plain_server(head)
    port = head.bind_to_random_port("tcp://127.0.0.1")
    member, member_log = start("member-serve", serve_args(["--process", "1", "--join",
                                                           "127.0.0.1:%d" % port]))

    def next_from_member(kinds, seconds):
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            if head.poll(50):
                peer, m = head.recv_multipart()
                if kind_of(m) in kinds:
                    return peer, m
        return None, None

    peer, j = next_from_member((JOIN,), 20)
    if j is None:
        fail("4. the member never joined the fake head")
    at = 16
    (n,) = struct.unpack_from("<H", j, at)
    at += 2 + n + 4
    (n,) = struct.unpack_from("<H", j, at)
    at += 2 + n
    (n,) = struct.unpack_from("<H", j, at)
    at += 2 + n + 8
    (incarnation,) = struct.unpack_from("<Q", j, at)
    head.send_multipart([peer, control(WELCOME, 0, incarnation)])
    head.send_multipart([peer, command(CMD_START, 77, a=1, tile=0)])
    answer = None
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and answer is None:
        head.send_multipart([peer, control(BEAT, 0, incarnation)])
        _, m = next_from_member((COMMAND,), 0.3)
        if m is not None and parse_command(m)[0][0] == CMD_READY:
            answer = m
    if answer is None:
        fail("4. no answer to a Start with tile size 0")
    fields, why = parse_command(answer)
    if fields[3] != 0 or "tile size 0" not in why:
        fail("4. a Start with tile size 0 was not refused: Ready %d %r" % (fields[3], why))
    time.sleep(1)
    if member.poll() is not None:
        fail("4. the member exited (%s) after a Start with tile size 0" % member.returncode)
    head.send_multipart([peer, command(CMD_SHUTDOWN, 0)])
    try:
        rc = member.wait(timeout=15)
    except subprocess.TimeoutExpired:
        fail("4. the member did not stop on the head's Shutdown")
    if rc != 0:
        fail("4. the member exited %d on the head's Shutdown" % rc)
    print("4. a Start with tile size 0: refused ('%s'), the member alive, then stopped with "
          "exit 0" % why, flush=True)
    head.close()


watch = threading.Timer(WATCHDOG_S, watchdog)
watch.daemon = True
watch.start()
for signum in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
    signal.signal(signum, lambda s, f: (kill_all(), os._exit(128 + s)))
try:
    serve, port = attack_flood()
    attack_captures(serve, port)
    attack_member_that_never_arrives()
    attack_bad_start()
    print("all attacks survived in %.1f s" % (time.monotonic() - started), flush=True)
    cleanup()
    shutil.rmtree(work, ignore_errors=True)
except SystemExit:
    raise
except BaseException as e:
    import traceback
    traceback.print_exc()
    fail("%s: %s" % (type(e).__name__, e))
