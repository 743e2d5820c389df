#!/usr/bin/python3
"""Hostile Modbus TCP clients against `maglev-hil serve` while the stage levitates.

Issue 17, item 4. The stage is homed and levitated (Ready); then, for
ATTACK_S seconds, these attack the server at once:

  * 100 concurrent connections that connect and send nothing;
  * a client that sends a valid request one byte a second;
  * a truncated MBAP header (3 bytes), a frame that announces 100 bytes and
    sends 3, an oversized MBAP length (0xFFFF), a wrong protocol id, garbage;
  * writes to read-only and unmapped registers, out-of-range values (operator
    and, with the documented engineer key, gains beyond their range, NaN, and
    an f32 cut in half), illegal function codes.

Meanwhile a well-behaved client reads status.state / status.fault every
20 ms on its own connection. Promises checked:

  * every malformed request that gets an answer gets the exception it
    should (01 / 02 / 03; 06 would be busy), never a normal reply;
  * the well-behaved client is answered every time, within 50 ms;
  * the stage stays Ready with no fault, throughout and after;
  * the persisted configuration (`stagectl config export`) is unchanged;
  * the network cannot take a servo tick: the work of one Modbus poll
    between two ticks stays within its bound, counted in system calls
    (serve's `max system calls per poll`, bounded by the connection limit
    and the per-client frame limit). Counted, not timed: on a shared or
    virtual machine, both the wall time and the thread CPU time of a poll
    hold preemption and hypervisor steal (a CPU-time bound failed CI for that
    reason). The deadline misses and the poll's CPU time are printed for a
    quiet phase and for the attack, not asserted.

The 50 ms answer limit is the product's promise and is asserted in the
host build. The sanitizer build passes a wider limit (GOOD_LIMIT_MS, 200):
ASan's instrumented server plus a loaded CI machine put a single answer at
52.8 ms once (worst of ~650, the rest near 1 ms), which says nothing about
the product; every other promise is checked unchanged there.

usage: hostile_levitated.py MAGLEV_HIL STAGECTL WORKDIR [GOOD_LIMIT_MS]
"""
import os
import random
import re
import signal
import socket
import struct
import subprocess
import sys
import threading
import time

ATTACK_S = 8.0
GOOD_PERIOD_S = 0.02
QUIET_S = 4.0

hil, stagectl, work = sys.argv[1], sys.argv[2], sys.argv[3]
GOOD_LIMIT_S = (float(sys.argv[4]) if len(sys.argv) > 4 else 50.0) / 1e3
os.makedirs(work, exist_ok=True)
flash = os.path.join(work, "flash.bin")
if os.path.exists(flash):
    os.remove(flash)

failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL:", msg, flush=True)


# --- the register map, from stagectl (the one source), not copied here -------
reg = {}
for line in subprocess.run([stagectl, "registers"], check=True, capture_output=True, text=True).stdout.splitlines():
    parts = line.split()
    if len(parts) >= 2 and parts[0].isdigit():
        reg[parts[1]] = int(parts[0])
for name in ("status.state", "status.fault", "cmd.axis", "gain.z.kp", "access.key"):
    assert name in reg, name
unmapped = next(a for a in range(60000, 65535) if a not in reg.values())

serve = subprocess.Popen([hil, "serve", "--modbus-tcp", "127.0.0.1:0", "--flash", flash, "--duration", "120"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
line = serve.stdout.readline()
m = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
if not m:
    print(line, serve.stderr.read())
    sys.exit("serve did not start")
port = int(m.group(1))
stderr_lines = []
threading.Thread(target=lambda: stderr_lines.extend(serve.stderr), daemon=True).start()


def ctl(*args, check=True):
    r = subprocess.run([stagectl, "--tcp", f"127.0.0.1:{port}", *args], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise SystemExit(f"stagectl {' '.join(args)}: rc {r.returncode}: {r.stdout}{r.stderr}")
    return r


# --- raw Modbus TCP ------------------------------------------------------------
def mbap(tid, pdu, unit=1, proto=0, length=None):
    return struct.pack(">HHHB", tid, proto, len(pdu) + 1 if length is None else length, unit) + pdu


def recv_reply(s, timeout):
    s.settimeout(timeout)
    head = b""
    while len(head) < 7:
        chunk = s.recv(7 - len(head))
        if not chunk:
            return None
        head += chunk
    n = struct.unpack(">H", head[4:6])[0] - 1
    body = b""
    while len(body) < n:
        chunk = s.recv(n - len(body))
        if not chunk:
            return None
        body += chunk
    return body


def connect():
    s = socket.create_connection(("127.0.0.1", port), timeout=2)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def request(pdu, expect_exception=None, unit=1, tries=20):
    """One request on a fresh connection; retried while the server sheds the
    connection (the connection limit with silent clients holding slots)."""
    for _ in range(tries):
        try:
            s = connect()
            s.sendall(mbap(random.randrange(65536), pdu, unit))
            body = recv_reply(s, 2.0)
            s.close()
        except (ConnectionError, socket.timeout, OSError):
            body = None
        if body is not None:
            break
        time.sleep(0.2)
    if body is None:
        fail(f"no reply to {pdu.hex()} after {tries} tries")
        return None
    if expect_exception is not None:
        if not (body[0] & 0x80) or body[1] != expect_exception:
            fail(f"request {pdu.hex()}: reply {body.hex()}, expected exception {expect_exception:02x}")
    return body


def read_pdu(addr, count):
    return struct.pack(">BHH", 3, addr, count)


def write1_pdu(addr, value):
    return struct.pack(">BHH", 6, addr, value)


def write_f32_pdu(addr, raw32):
    return struct.pack(">BHHBI", 16, addr, 2, 4, raw32)


# --- levitate --------------------------------------------------------------------
ctl("--wait", "10", "home")
ctl("--wait", "20", "levitate")
st = ctl("status").stdout
if "Ready" not in st:
    sys.exit("stage not Ready before the attack:\n" + st)
before = os.path.join(work, "config_before.txt")
after = os.path.join(work, "config_after.txt")
ctl("config", "export", before)


def misses_now():
    # serve's once-a-second status line carries the cumulative deadline misses.
    for l in reversed(list(stderr_lines)):
        m = re.search(r"misses=(\d+)", l)
        if m:
            return int(m.group(1))
    return 0


print(f"serve on port {port}: levitated (Ready); quiet for {QUIET_S} s, then attacking for {ATTACK_S} s", flush=True)

stop = threading.Event()
good = {"n": 0, "worst": 0.0, "bad_state": [], "errors": 0}


def good_client():
    s = connect()
    tid = 0
    while not stop.is_set():
        tid = (tid + 1) & 0xFFFF
        t0 = time.monotonic()
        try:
            s.sendall(mbap(tid, read_pdu(reg["status.state"], 2)))
            body = recv_reply(s, 1.0)
        except (OSError, socket.timeout):
            body = None
        dt = time.monotonic() - t0
        if body is None or body[0] != 3:
            good["errors"] += 1
            try:
                s.close()
                s = connect()
            except OSError:
                pass
        else:
            state, fault = struct.unpack(">HH", body[2:6])
            good["n"] += 1
            good["worst"] = max(good["worst"], dt)
            if fault != 0 or state != ready_state:
                good["bad_state"].append((round(time.monotonic(), 3), state, fault))
        time.sleep(GOOD_PERIOD_S)
    s.close()


def silent_flood(sockets):
    for _ in range(100):
        try:
            sockets.append(connect())
        except OSError:
            pass


def slow_client():
    try:
        s = connect()
        for b in mbap(7, read_pdu(reg["status.state"], 1)):
            if stop.is_set():
                break
            s.send(bytes([b]))
            time.sleep(1.0)
        s.close()
    except OSError:
        pass  # closed by the server's frame timeout: the promise


def raw_attacks():
    rng = random.Random(17)
    frames = [
        b"\x00\x01\x00",                                    # truncated MBAP header
        mbap(2, b"\x03\x00", length=100),                   # announces 100, sends 3
        struct.pack(">HHHB", 3, 0, 0xFFFF, 1) + b"\x03" * 40,  # oversized length
        mbap(4, read_pdu(100, 1), proto=0x1234),            # wrong protocol id
        bytes(rng.randrange(256) for _ in range(300)),      # garbage
        mbap(5, b"\x11" + b"\x00" * 4),                     # 0x11 with trailing bytes
    ]
    while not stop.is_set():
        for f in frames:
            try:
                s = connect()
                s.sendall(f)
                time.sleep(0.05)
                s.close()
            except OSError:
                pass
        time.sleep(0.1)


# Ready's value, read once before the attack (stagectl prints "Ready (N)").
ready_state = int(re.search(r"Ready \((\d+)\)", st).group(1))

m0 = misses_now()
quiet_t0 = time.monotonic()
good_quiet = threading.Thread(target=good_client)
good_quiet.start()
time.sleep(QUIET_S)
stop.set()
good_quiet.join()
stop.clear()
time.sleep(1.1)  # the next status line
quiet_misses = misses_now() - m0
quiet_worst = good["worst"]
good.update(n=0, worst=0.0)
m1 = misses_now()
attack_t0 = time.monotonic()

held = []
threads = [threading.Thread(target=good_client), threading.Thread(target=slow_client),
           threading.Thread(target=raw_attacks)]
for t in threads:
    t.start()
silent_flood(held)
print(f"  {len(held)} silent connections opened", flush=True)
time.sleep(1.2)  # silent for longer than evict_after: newcomers may take their slots

t_end = time.monotonic() + ATTACK_S
rounds = 0
while time.monotonic() < t_end:
    rounds += 1
    request(write1_pdu(reg["status.state"], 0), expect_exception=0x02)      # read-only
    request(read_pdu(unmapped, 1), expect_exception=0x02)                    # unmapped read
    request(write1_pdu(unmapped, 1), expect_exception=0x02)                  # unmapped write
    request(write1_pdu(reg["cmd.axis"], 9), expect_exception=0x03)          # out of range
    request(read_pdu(reg["status.state"], 0), expect_exception=0x03)        # count 0
    request(read_pdu(reg["status.state"], 126), expect_exception=0x03)      # count > 125
    request(write_f32_pdu(reg["gain.z.kp"], 0x4B000000), expect_exception=0x01)  # gains: engineer only
    for fc in (0x07, 0x2B, 0x99, 0x00):
        request(bytes([fc, 0, 0, 0, 1]), expect_exception=0x01)             # illegal functions
    # With the engineer key: gains beyond their range, NaN, half an f32 -> 02/03.
    request(write1_pdu(reg["access.key"], 0x4E47))
    request(write_f32_pdu(reg["gain.z.kp"], struct.unpack(">I", struct.pack(">f", 1e8))[0]),
            expect_exception=0x03)
    request(write_f32_pdu(reg["gain.z.kp"], 0x7FC00000), expect_exception=0x03)     # NaN
    request(write1_pdu(reg["gain.z.kp"], 0x4B00), expect_exception=0x02)            # half an f32
    request(write1_pdu(reg["access.key"], 0))                                       # lock again
request(mbap(1, b"")[:0] + bytes([3, 0, 100, 0, 1]), unit=0)  # unit 0 is answered (never silent)
stop.set()
for t in threads:
    t.join()
for s in held:
    s.close()
attack_s = time.monotonic() - attack_t0
time.sleep(1.1)
attack_misses = misses_now() - m1

# --- after ---------------------------------------------------------------------------
st = ctl("status").stdout
if "Ready" not in st or not re.search(r"fault\s*=\s*0\b", st):
    fail("stage not Ready without fault after the attack:\n" + st)
ctl("config", "export", after)
b_lines = [l for l in open(before) if not l.startswith("#")]
a_lines = [l for l in open(after) if not l.startswith("#")]
if b_lines != a_lines:
    fail("configuration changed: " + "".join(l for l in a_lines if l not in b_lines))
if good["n"] == 0:
    fail("the well-behaved client was never answered")
if good["errors"]:
    fail(f"the well-behaved client lost {good['errors']} requests")
if good["worst"] > GOOD_LIMIT_S:
    fail(f"the well-behaved client waited {good['worst'] * 1e3:.1f} ms (limit {GOOD_LIMIT_S * 1e3:.0f} ms)")
if good["bad_state"]:
    fail(f"state/fault left Ready/0 during the attack: {good['bad_state'][:5]}")

serve.send_signal(signal.SIGTERM)
serve.wait(timeout=20)
time.sleep(0.2)
summary = next((l for l in stderr_lines if "stopped after" in l), "")
mstats = next((l for l in stderr_lines if "max system calls per poll" in l), "")
m = re.search(r"poll CPU max (\d+) us", summary)
k = re.search(r"(\d+) requests answered, max system calls per poll (\d+) \(bound (\d+)\)", mstats)
if not m or not k:
    fail("no serve summary: " + "".join(stderr_lines[-3:]))
else:
    poll_cpu_us = int(m.group(1))
    requests, syscalls, bound = (int(g) for g in k.groups())
    print(f"  serve: {requests} Modbus requests answered; max system calls in one poll {syscalls} (bound {bound}); "
          f"max CPU time of one poll {poll_cpu_us} us (informative)")
    print(f"  deadline misses (wall clock, includes preemption): quiet {quiet_misses} in {QUIET_S:.0f} s, "
          f"under attack {attack_misses} in {attack_s:.1f} s")
    print("  " + mstats.strip())
    if syscalls > bound:
        fail(f"one Modbus poll made {syscalls} system calls (bound {bound})")
print(f"  well-behaved client, quiet: worst {quiet_worst * 1e3:.2f} ms")
print(f"  {rounds} attack rounds; well-behaved client: {good['n']} reads, worst {good['worst'] * 1e3:.2f} ms, "
      f"{good['errors']} lost; state Ready, fault 0 throughout: {not good['bad_state']}; "
      f"configuration unchanged: {b_lines == a_lines}")
if failures:
    print(f"hostile_levitated: {len(failures)} failures")
    sys.exit(1)
print("hostile_levitated: passed")
