#!/usr/bin/python3
"""The wall service's authentication and encryption, tried as an attacker would on one host
(docs/security.md, "The wall service"). Each attack, then a good job that still works.

Usage: service_security.py LAYOUT tokens|curve|relay   (env DFBWALL, COMPARE, MPIEXEC; LAYOUT: one wall process)

  1. serve --token-file FILE creates FILE mode 0600 with a fresh token; the token is in no log and
     no command line.
  2. Unauthenticated peers cannot make the wall hold memory: raw ZMTP connections to the
     directory and piece ports announce a 1 GiB frame during the handshake and trickle 8 MiB;
     the wall process's peak RSS (VmHWM) rises by at most a few MiB. Peers with a wrong token
     get no message through. A good job then equals the one-process render.
  3. A job with a wrong token is refused at the handshake, at once, saying so; a token file other
     users may read is refused.
  4. CURVE (dfbwall keygen, serve --curve, --server-key): a job works, directly and through a
     relay serving CURVE; a tcpdump of the wall's ports shows neither the token nor a run of the
     job's pixels, which the same capture of a PLAIN job does show; a job pinning another key is
     refused within seconds.
  5. A relay with the token: hundreds of tokenless connections do not keep a good job out.
  6. --advertise: an address the process does not listen on is refused; one it does is what
     jobs are told.
"""
import os
import re
import secrets
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

layout = os.path.abspath(sys.argv[1])
# tokens (1-3), curve (4), relay (5-6): three tests that ctest runs side by side.
part = sys.argv[2] if len(sys.argv) > 2 else ""
if part not in ("tokens", "curve", "relay"):
    sys.exit("usage: service_security.py LAYOUT tokens|curve|relay")
dfbwall = os.environ["DFBWALL"]
compare = os.environ["COMPARE"]
mpiexec = os.environ.get("MPIEXEC") or "mpirun"
work = tempfile.mkdtemp(prefix="dfbwall-security-")
# A home of its own: the default token file of this test is nobody else's.
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", HOME=work)
env.pop("XDG_STATE_HOME", None)
env.pop("DFBWALL_TOKEN", None)
ctx = zmq.Context()
procs = []
logs = {}
WATCHDOG_S = 220
TIMEOUT_S = 4


def kill_all():
    for p in procs:
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def print_logs():
    for name, path in logs.items():
        try:
            with open(path, errors="replace") as f:
                print("--- %s ---\n%s" % (name, f.read()[-4000:]), flush=True)
        except OSError:
            pass


def fail(why):
    print("FAIL: " + why, flush=True)
    print_logs()
    kill_all()
    ctx.destroy(linger=0)
    sys.exit(1)


def watchdog():
    print("FAIL: the test took more than %d s" % WATCHDOG_S, flush=True)
    print_logs()
    kill_all()
    os._exit(1)


def start(args, name, extra_env=None):
    path = os.path.join(work, name + ".log")
    logs[name] = path
    with open(path, "w") as out:
        p = subprocess.Popen(args, env=dict(env, **(extra_env or {})), stdout=out,
                             stderr=subprocess.STDOUT, start_new_session=True)
    procs.append(p)
    return p


def log_of(name):
    with open(logs[name], errors="replace") as f:
        return f.read()


def wait_for(name, needle, proc, seconds=30):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        text = log_of(name)
        if needle in text:
            return text
        if proc.poll() is not None:
            fail("%s exited (%s) before saying %r" % (name, proc.returncode, needle))
        time.sleep(0.1)
    fail("%s never said %r" % (name, needle))


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def serve(name, port, *extra):
    p = start([dfbwall, "serve", "--wall", layout, "--process", "0", "--listen",
               "127.0.0.1:%d" % port, "--offscreen", "--timeout", str(TIMEOUT_S),
               "--capture-root", work] + list(extra), name)
    wait_for(name, "wall service on", p)
    return p


def stop(p):
    p.send_signal(signal.SIGUSR1)
    try:
        p.wait(timeout=15)
    except subprocess.TimeoutExpired:
        fail("a wall did not stop within 15 s of SIGUSR1")


def job(name, connect, *extra, frames=2, renderer="pattern", extra_env=None, ranks=2):
    capture = os.path.join(work, name)
    p = start([mpiexec, "--bind-to", "none", "-np", str(ranks), dfbwall, "--connect", connect,
               "--renderer", renderer, "--frames", str(frames), "--quiet", "--timeout", "20",
               "--capture", capture] + list(extra), name, extra_env)
    try:
        rc = p.wait(timeout=90)
    except subprocess.TimeoutExpired:
        fail("job %s hung" % name)
    return rc, capture


reference = None


def good_job(name, connect, *extra):
    global reference
    rc, capture = job(name, connect, *extra)
    if rc != 0:
        fail("the good job %s exited %d" % (name, rc))
    if reference is None:
        reference = os.path.join(work, "full.png")
        size = subprocess.run([compare, "--info", layout], capture_output=True, text=True,
                              env=env).stdout.split()[1]
        r = start([mpiexec, "--bind-to", "none", "-np", "1", dfbwall, "--renderer", "pattern",
                   "--frames", "2", "--size", size, "--image", reference, "--quiet"], "reference")
        if r.wait(timeout=60) != 0:
            fail("the one-process reference render failed")
    if subprocess.run([compare, layout, capture, reference, "2"], env=env).returncode != 0:
        fail("the good job %s's captures differ from the one-process render" % name)
    return capture


def vm_hwm_kib(pid):
    with open("/proc/%d/status" % pid) as f:
        return int(re.search(r"VmHWM:\s+(\d+)", f.read()).group(1))


def listening_ports(pid):
    out = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True).stdout
    return sorted({int(m.group(1)) for line in out.splitlines() if "pid=%d," % pid in line
                   for m in [re.search(r":(\d+)\s", line)] if m})


# A ZMTP 3.1 greeting of a PLAIN client: the server goes on to the handshake.
GREETING = (b"\xff" + b"\x00" * 8 + b"\x7f" + b"\x03\x01" + b"PLAIN".ljust(20, b"\x00") +
            b"\x00" + b"\x00" * 31)


def big_frame_attack(port, announce, trickle):
    """Greeting, then a command frame announcing `announce` bytes, then `trickle` bytes of it.
    Returns how many bytes the wall took before it closed the connection."""
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    sent = 0
    try:
        s.sendall(GREETING)
        s.sendall(b"\x06" + struct.pack(">Q", announce))  # a long command frame
        chunk = os.urandom(64 << 10)
        while sent < trickle:
            s.sendall(chunk)
            sent += len(chunk)
    except OSError:
        pass
    finally:
        s.close()
    return sent


def plain_dealer(endpoint, token):
    s = ctx.socket(zmq.DEALER)
    s.setsockopt(zmq.LINGER, 0)
    s.plain_username = b"dfbwall"
    s.plain_password = token.encode()
    s.connect(endpoint)
    return s


def send_if_it_can(s, message):
    """Never blocks: a refused peer's socket may already have no pipe to queue on (its handshake
    failed before this call), where a blocking send waits for a peer that never comes."""
    try:
        s.send(message, zmq.NOBLOCK)
    except zmq.Again:
        pass


def hello():
    text = lambda b: struct.pack("<H", len(b)) + b
    return (struct.pack("<IHHQ", 0x57424644, 4, 1, 0) + text(b"") + text(b"attacker") +
            struct.pack("<II", 1, 64) + struct.pack("<BBBB", 0, 90, 0, 0) + struct.pack("<I", 2) +
            text(b"") + struct.pack("<I", 0) + struct.pack("<Biiii", 0, 0, 0, 0, 0) + text(b"") +
            struct.pack("<B", 0) + text(b"") + text(b""))


def pcap(name, ports):
    """tcpdump of loopback, the wall's ports only (other tests may run pattern jobs meanwhile)."""
    path = os.path.join(work, name + ".pcap")
    expression = " or ".join("tcp port %d" % p for p in ports)
    p = start(["tcpdump", "-i", "lo", "-U", "-s", "0", "-w", path, expression], name + "-tcpdump")
    time.sleep(1.0)  # tcpdump is listening
    if p.poll() is not None:
        fail("tcpdump did not start: " + log_of(name + "-tcpdump"))
    return p, path


def end_pcap(p, path):
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    p.wait(timeout=10)
    with open(path, "rb") as f:
        return f.read()


def pixel_runs(capture):
    """Runs of 16 pixels (64 bytes) of the job's last frame that a raw batch carries as they are:
    inside one 64-pixel tile, where the picture changes (at least 2 distinct pixels)."""
    png = os.path.join(capture, sorted(os.listdir(capture))[0], "frame-000002.png")
    raw = os.path.join(work, "pixels.raw")
    w, h = map(int, subprocess.run([compare, "--raw", png, raw], capture_output=True, text=True,
                                   env=env, check=True).stdout.split())
    with open(raw, "rb") as f:
        data = f.read()
    runs = []
    for y in range(3, h, 7):
        for x in range(0, w - 16, 16):
            if x % 64 + 16 > 64:
                continue
            run = data[(y * w + x) * 4:(y * w + x + 16) * 4]
            if len({run[i:i + 4] for i in range(0, 64, 4)}) >= 2 and run not in runs:
                runs.append(run)
    if not runs:
        fail("the pattern has no run of 16 pixels with 2 colours")
    return runs[:40]


timer = threading.Timer(WATCHDOG_S, watchdog)
timer.daemon = True
timer.start()
try:
    token_file = os.path.join(work, "wall-token")
    if part == "tokens":
        # ---- 1. the token file -----------------------------------------------------------------
        port = free_port()
        wall = serve("serve", port, "--token-file", token_file)
        mode = os.stat(token_file).st_mode & 0o777
        if mode != 0o600:
            fail("serve created the token file with mode %o, not 600" % mode)
        with open(token_file) as f:
            token = f.read().strip()
        if not re.fullmatch(r"[0-9a-f]{64}", token):
            fail("the token file holds %r, not 64 hex digits" % token)
        with open("/proc/%d/cmdline" % wall.pid, "rb") as f:
            if token.encode() in f.read():
                fail("the token is on serve's command line")
        print("1. serve --token-file: created mode 600, a 64-digit token, not on the command line",
              flush=True)

        # ---- 2. memory an unauthenticated peer can cost; wrong tokens ----------------------------
        ports = listening_ports(wall.pid)
        if port not in ports or len(ports) < 2:
            fail("expected the directory and a piece port among serve's ports, got %s" % ports)
        time.sleep(0.5)
        before = vm_hwm_kib(wall.pid)
        took = []
        for p in ports:  # the directory socket and the piece socket
            for _ in range(4):
                took.append(big_frame_attack(p, 1 << 30, 8 << 20))
        liars = [plain_dealer("tcp://127.0.0.1:%d" % port, "wrong") for _ in range(20)]
        for s in liars:
            send_if_it_can(s, hello())
        time.sleep(2.0)
        answered = sum(1 for s in liars if s.poll(0))
        for s in liars:
            s.close()
        after = vm_hwm_kib(wall.pid)
        grew_mib = (after - before) / 1024.0
        if answered:
            fail("%d wrong-token connections got an answer" % answered)
        if grew_mib > 4:
            fail("8 connections announcing 1 GiB raised the wall's peak RSS by %.1f MiB" % grew_mib)
        if "refused a connection from 127.0.0.1 at the handshake" not in log_of("serve"):
            fail("the wall did not log the refused handshakes")
        print("2. 8 x 1 GiB frames announced (%d KiB sent before the wall hung up, at most), 20 "
              "wrong-token hellos unanswered: peak RSS %+.2f MiB" % (max(took) // 1024, grew_mib),
              flush=True)
        good_job("after-attacks", "127.0.0.1:%d" % port, "--token-file", token_file)
        print("   then a good job: captures equal the one-process render", flush=True)

        # ---- 3. wrong tokens on the job's side ----------------------------------------------------
        t0 = time.monotonic()
        rc, _ = job("wrong-token", "127.0.0.1:%d" % port, extra_env={"DFBWALL_TOKEN": "wrong"},
                    ranks=1)
        took_s = time.monotonic() - t0
        if rc == 0 or "refused the job at the handshake" not in log_of("wrong-token"):
            fail("a job with a wrong token: exit %d, %r" % (rc, log_of("wrong-token")[-300:]))
        if took_s > 15:
            fail("the wrong-token refusal took %.1f s" % took_s)
        loose = os.path.join(work, "loose-token")
        with open(loose, "w") as f:
            f.write(token + "\n")
        os.chmod(loose, 0o644)
        rc, _ = job("loose-token", "127.0.0.1:%d" % port, "--token-file", loose, ranks=1)
        if rc == 0 or "other users may read it" not in log_of("loose-token"):
            fail("a token file mode 644 was used: exit %d" % rc)
        for name in ("serve", "after-attacks", "wrong-token", "loose-token"):
            if token in log_of(name):
                fail("the token appears in the log of " + name)
        print("3. wrong token refused at the handshake in %.1f s; a 644 token file refused; the token "
              "in no log" % took_s, flush=True)

        stop(wall)
    else:  # the token file as serve makes it
        token = secrets.token_hex(32)
        fd = os.open(token_file, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        os.write(fd, (token + "\n").encode())
        os.close(fd)

    if part == "curve":
        port = free_port()
        wall = serve("serve", port, "--token-file", token_file)
        ports = listening_ports(wall.pid)
        # A PLAIN job under tcpdump: the control for 4 (its pixels and token are in clear).
        dump, path = pcap("plain", ports)
        capture = good_job("plain-wire", "127.0.0.1:%d" % port, "--token-file", token_file,
                           "--codec", "raw")
        wire = end_pcap(dump, path)
        runs = pixel_runs(capture)
        seen_plain = [r for r in runs if r in wire]
        if not seen_plain or token.encode() not in wire:
            fail("the PLAIN control: %d of %d pixel runs and %s token on the wire; the check for "
                 "CURVE would prove nothing" % (len(seen_plain), len(runs),
                                                "the" if token.encode() in wire else "no"))
        stop(wall)

        # ---- 4. CURVE ----------------------------------------------------------------------------
        keys, other = os.path.join(work, "keys"), os.path.join(work, "other-keys")
        for d in (keys, other):
            if subprocess.run([dfbwall, "keygen", d], env=env).returncode != 0:
                fail("dfbwall keygen %s failed" % d)
        if os.stat(os.path.join(keys, "wall-secret.key")).st_mode & 0o777 != 0o600:
            fail("keygen wrote the secret key readable by others")
        if subprocess.run([dfbwall, "keygen", keys], env=env, capture_output=True).returncode == 0:
            fail("keygen overwrote a key pair")
        port = free_port()
        wall = serve("serve-curve", port, "--token-file", token_file, "--curve", keys)
        dump, path = pcap("curve", listening_ports(wall.pid))
        capture = good_job("curve", "127.0.0.1:%d" % port, "--token-file", token_file, "--codec", "raw",
                           "--server-key", os.path.join(keys, "wall-public.key"))
        wire = end_pcap(dump, path)
        runs = pixel_runs(capture)
        leaked = [r for r in runs if r in wire]
        if token.encode() in wire or leaked:
            fail("with CURVE the wire shows %s token and %d of %d pixel runs" %
                 ("the" if token.encode() in wire else "no", len(leaked), len(runs)))
        t0 = time.monotonic()
        rc, _ = job("wrong-key", "127.0.0.1:%d" % port, "--token-file", token_file, "--server-key",
                    os.path.join(other, "wall-public.key"), ranks=1)
        took_s = time.monotonic() - t0
        if rc == 0 or "no handshake with the wall" not in log_of("wrong-key"):
            fail("a job pinning another key: exit %d, %r" % (rc, log_of("wrong-key")[-300:]))
        if took_s > 15:
            fail("the job pinning another key took %.1f s to fail" % took_s)
        rc, _ = job("plain-at-curve", "127.0.0.1:%d" % port, "--token-file", token_file, ranks=1)
        if rc == 0:
            fail("a PLAIN job was accepted by a CURVE wall")
        print("4. CURVE: the job's captures equal the render; on the wire no token and 0 of %d pixel "
              "runs (PLAIN: %d of %d and the token); another key refused in %.1f s" %
              (len(runs), len(seen_plain), len(runs), took_s), flush=True)
        # Through a relay that pins the wall's key and serves CURVE itself with the same key pair.
        relay_port = free_port()
        relay = start([dfbwall, "relay", "--listen", "127.0.0.1:%d" % relay_port, "--wall",
                       "127.0.0.1:%d" % port, "--token-file", token_file, "--server-key",
                       os.path.join(keys, "wall-public.key"), "--curve", keys, "--timeout", "30"],
                      "relay-curve")
        wait_for("relay-curve", "relay on", relay)
        good_job("curve-relay", "127.0.0.1:%d" % relay_port, "--token-file", token_file,
                 "--server-key", os.path.join(keys, "wall-public.key"))
        relay.send_signal(signal.SIGUSR1)
        relay.wait(timeout=10)
        print("   a job through a CURVE relay to the CURVE wall equals the render", flush=True)
        stop(wall)
        # A joining process pins the head's key from its own key folder: another pair is refused at
        # once with the reason, the right one joins.
        layout4 = os.path.join(os.path.dirname(layout), "2x2.toml")
        port = free_port()
        head = start([dfbwall, "serve", "--wall", layout4, "--process", "0", "--listen",
                      "127.0.0.1:%d" % port, "--offscreen", "--timeout", str(TIMEOUT_S),
                      "--token-file", token_file, "--curve", keys], "head-curve")
        wait_for("head-curve", "wall service on", head)
        member = lambda name, key_dir: start(
            [dfbwall, "serve", "--wall", layout4, "--process", "1", "--join", "127.0.0.1:%d" % port,
             "--offscreen", "--timeout", str(TIMEOUT_S), "--token-file", token_file, "--curve",
             key_dir], name)
        stranger = member("member-other-key", other)
        try:
            rc = stranger.wait(timeout=20)
        except subprocess.TimeoutExpired:
            fail("a joining process with another key pair neither joined nor gave up")
        if rc == 0 or "the handshake broke off" not in log_of("member-other-key"):
            fail("a joining process with another key pair: exit %d, %r" %
                 (rc, log_of("member-other-key")[-300:]))
        joined = member("member-curve", keys)
        wait_for("member-curve", "joined the wall", joined)
        stop(joined)
        stop(head)
        print("   a joining process with another key pair exits 1 naming the handshake; with the "
              "wall's it joins", flush=True)

    if part == "relay":
        # ---- 5. a relay and tokenless connections --------------------------------------------------
        port = free_port()
        wall = serve("serve-relayed", port, "--token-file", token_file)
        relay_port = free_port()
        relay = start([dfbwall, "relay", "--listen", "127.0.0.1:%d" % relay_port, "--wall",
                       "127.0.0.1:%d" % port, "--token-file", token_file, "--timeout", "30"], "relay")
        wait_for("relay", "relay on", relay)
        strangers = []
        for i in range(300):
            s = ctx.socket(zmq.DEALER)
            s.setsockopt(zmq.LINGER, 0)
            if i % 2:
                s.plain_username = b"dfbwall"
                s.plain_password = b"wrong"
            s.connect("tcp://127.0.0.1:%d" % relay_port)
            send_if_it_can(s, hello())
            strangers.append(s)
        time.sleep(2.0)
        good_job("through-relay", "127.0.0.1:%d" % relay_port, "--token-file", token_file)
        answered = sum(1 for s in strangers if s.poll(0))
        for s in strangers:
            s.close()
        if answered:
            fail("%d tokenless connections to the relay got an answer" % answered)
        print("5. relay: 300 tokenless connections held nothing; a good job through it equals the "
              "render", flush=True)
        relay.send_signal(signal.SIGUSR1)
        relay.wait(timeout=10)
        stop(wall)

        # ---- 6. --advertise ------------------------------------------------------------------------
        port = free_port()
        bad = start([dfbwall, "serve", "--wall", layout, "--process", "0", "--listen",
                     "127.0.0.1:%d" % port, "--advertise", "10.254.254.254", "--offscreen",
                     "--token-file", token_file], "advertise-bad")
        if bad.wait(timeout=30) == 0 or "--advertise 10.254.254.254: this process does not listen " \
                                         "there" not in log_of("advertise-bad"):
            fail("serve advertised an address it does not listen on")
        port = free_port()
        good = start([dfbwall, "serve", "--wall", layout, "--process", "0", "--listen",
                      "0.0.0.0:%d" % port, "--advertise", "127.0.0.1", "--offscreen",
                      "--token-file", token_file], "advertise-good")
        wait_for("advertise-good", "wall service on 127.0.0.1:%d" % port, good)
        stop(good)
        print("6. --advertise: an address not listened on refused; 127.0.0.1 on 0.0.0.0 advertised",
              flush=True)
    kill_all()
    ctx.destroy(linger=0)
    shutil.rmtree(work, ignore_errors=True)
    print("PASS")
except SystemExit:
    raise
except BaseException as e:
    import traceback
    traceback.print_exc()
    fail("%s: %s" % (type(e).__name__, e))
