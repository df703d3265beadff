"""Soak: the gateway under malformed Modbus frames, bad SDO requests, idle connections and kill -9.

Starts `twin can-hub` and `twin serve house1` (Modbus TCP + CANopen over the hub, recording) on
loopback, then, each phase bounded in count and time:
  1. a normal client polls read(10 input registers) every 10 ms: p99 latency "before";
  2. 100,000 malformed Modbus TCP frames of 16 kinds, in batches per connection (each batch
     ends with a proper read that must be answered); log lines per 1,000 frames;
  3. 10,000 bad SDO requests of 10 kinds over the hub: right abort codes, wrong ones, no answer;
  4. 1,000 idle connections held open while the normal client polls: p99 "during", then "after";
  5. RSS growth of the gateway over phases 2-4, crashes (the process alive, no traceback);
  6. a second gateway recording at 1x is killed with SIGKILL: simulated seconds missing from
     signals.csv (the recorder flushes every second).
Run: python benchmarks/gateway_soak.py [--frames 100000] [--sdo 10000] [--idle 1000]
"""
import argparse
import random
import re
import resource
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import can
import numpy as np
from pymodbus.client import ModbusTcpClient

from gateway.maps.loader import load_map
from gateway.loopback import free_port, wait_port

REPO = Path(__file__).resolve().parents[1]
CHP = load_map(REPO / "devices/chp_neotower2.toml")
IO = load_map(REPO / "devices/storage_io.toml")
NODE = CHP.canopen.node_id


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def twin(*args: str, **popen) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "cli.main", *args], cwd=REPO, text=True, **popen)


# ------------------------------------------------------------------------------ Modbus frames
def mbap(tid: int, unit: int, pdu: bytes, pid: int = 0, length: int | None = None) -> bytes:
    return struct.pack(">HHHB", tid, pid, len(pdu) + 1 if length is None else length, unit) + pdu


def read(tid: int, unit: int = IO.unit_id) -> bytes:
    return mbap(tid, unit, struct.pack(">BHH", 4, 0, 10))


#: kinds a batch may hold anywhere (the server can cut each off the stream by itself)
INLINE = {
    "bad protocol id": lambda r: mbap(1, IO.unit_id, struct.pack(">BHH", 3, 0, 1), pid=r.randint(1, 0xFFFF)),
    "length 0": lambda r: mbap(1, IO.unit_id, b"", length=0)[:6],
    "length 1": lambda r: mbap(1, IO.unit_id, b"", length=1),
    "unknown function 0x41": lambda r: mbap(1, IO.unit_id, b"\x41\x00\x00"),
    "unknown function 0x64": lambda r: mbap(1, CHP.unit_id, b"\x64"),
    "function 0": lambda r: mbap(1, IO.unit_id, b"\x00\x00\x01"),
    "exception PDU as request": lambda r: mbap(1, IO.unit_id, b"\x83\x02"),
    "read with 1-byte body": lambda r: mbap(1, IO.unit_id, b"\x03\x00"),
    "read count 0": lambda r: mbap(1, IO.unit_id, struct.pack(">BHH", 4, 0, 0)),
    "read count 200": lambda r: mbap(1, IO.unit_id, struct.pack(">BHH", 4, 0, 200)),
}
#: kinds sent last on a connection, after the check read: those that leave the stream out of step,
#: and requests the server decodes (their answers would interleave with the check read's; every
#: frame of a segment is answered since the server queues them, benchmarks/modbus_pipelining.py)
LAST = {
    "unknown unit": lambda r: mbap(1, 0x42, struct.pack(">BHH", 4, 0, 1)),
    "FC16 byte count mismatch": lambda r: mbap(1, CHP.unit_id, struct.pack(">BHHB", 16, 100, 2, 9) + b"\0" * 4),
    "FC43 bad MEI type": lambda r: mbap(1, CHP.unit_id, b"\x2b\x0f\x01\x00"),
    "length too long": lambda r: mbap(1, IO.unit_id, b"\x03\x00\x00", length=0xFFFF),
    "random garbage": lambda r: bytes(r.getrandbits(8) for _ in range(r.randint(1, 40))),
    "truncated frame": lambda r: mbap(1, IO.unit_id, struct.pack(">BHH", 4, 0, 1))[:9],
}


def answer(s: socket.socket, tid: int, timeout: float = 2.0) -> bytes | None:
    buffer, end = b"", time.monotonic() + timeout
    while time.monotonic() < end:
        while len(buffer) >= 6 and len(buffer) >= 6 + struct.unpack(">H", buffer[4:6])[0]:
            size = 6 + struct.unpack(">H", buffer[4:6])[0]
            frame, buffer = buffer[:size], buffer[size:]
            if struct.unpack(">H", frame[:2])[0] == tid:
                return frame
        try:
            chunk = s.recv(65536)
        except socket.timeout:
            return None
        if not chunk:
            return None
        buffer += chunk
    return None


def malformed_flood(port: int, frames: int, seconds: float) -> dict:
    rng = random.Random(15)
    inline, last = list(INLINE.items()), list(LAST.items())
    sent: dict[str, int] = {}
    bad_checks = batches = 0
    end = time.monotonic() + seconds
    batch = 499
    while sum(sent.values()) < frames and time.monotonic() < end:
        n = min(batch, frames - sum(sent.values()) - 1)
        chosen = [inline[rng.randrange(len(inline))] for _ in range(max(n, 0))]
        tid = 1000 + batches % 60000
        payload = b"".join(make(rng) for _, make in chosen) + read(tid)
        with socket.create_connection(("127.0.0.1", port), timeout=2.0) as s:
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            s.sendall(payload)
            frame = answer(s, tid)
            if frame is None or frame[7] != 4 or len(frame) != 9 + 20:   # 10 registers
                bad_checks += 1
            name, make = last[batches % len(last)]
            s.sendall(make(rng))
        for name_, _ in chosen:
            sent[name_] = sent.get(name_, 0) + 1
        sent[name] = sent.get(name, 0) + 1
        batches += 1
    return {"sent": sent, "batches": batches, "bad_checks": bad_checks}


# ------------------------------------------------------------------------------ SDO requests
def sdo(ccs_byte: int, index: int, sub: int, data: bytes = b"") -> bytes:
    return bytes([ccs_byte]) + struct.pack("<HB", index, sub) + data.ljust(4, b"\0")


SDO_KINDS = {  # name: (request, expected abort code)
    "upload of a missing object": (sdo(0x40, 0x3000, 0), 0x06020000),
    "upload of a missing subindex": (sdo(0x40, 0x2100, 0x30), 0x06090011),
    "download to a read-only object": (sdo(0x2B, 0x1000, 0, b"\0\0"), 0x06010002),
    "upload of a write-only object": (sdo(0x40, 0x2F00, 1), 0x06010001),
    "download of a value too high": (sdo(0x2B, 0x2200, 1, b"\x02\x00"), 0x06090031),
    "download of the wrong length": (sdo(0x23, 0x2200, 1, b"\x01\0\0\0"), 0x06070010),
    "block upload": (bytes([0xA4]) + struct.pack("<HB", 0x1008, 0) + b"\x7f\0\0\0", 0x05040001),
    "block download": (bytes([0xC6]) + struct.pack("<HB", 0x2F00, 2) + b"\x02\0\0\0", 0x05040001),
    "command specifier 7": (sdo(0xE0, 0x1000, 0), 0x05040001),
    "short frame": (b"\x40\x00\x10", 0x05040001),
}


def bad_sdo(hub_port: int, count: int, seconds: float) -> dict:
    bus = can.Bus(interface="socketcand", channel="can0", host="127.0.0.1", port=hub_port,
                  tcp_tune=True, ignore_config=True)
    kinds = list(SDO_KINDS.items())
    result = {"tried": 0, "right": 0, "wrong": {}, "missing": {}, "slowest_ms": 0.0}
    end = time.monotonic() + seconds
    try:
        for i in range(count):
            if time.monotonic() > end:
                break
            name, (data, code) = kinds[i % len(kinds)]
            t0 = time.perf_counter()
            bus.send(can.Message(arbitration_id=0x600 + NODE, data=data, is_extended_id=False))
            result["tried"] += 1
            got = None
            while time.perf_counter() - t0 < 0.5:
                msg = bus.recv(0.5)
                if msg is not None and msg.arbitration_id == 0x580 + NODE:
                    got = bytes(msg.data)
                    break
            if got is None:
                result["missing"][name] = result["missing"].get(name, 0) + 1
                continue
            result["slowest_ms"] = max(result["slowest_ms"], (time.perf_counter() - t0) * 1e3)
            if got[0] == 0x80 and struct.unpack_from("<L", got, 4)[0] == code:
                result["right"] += 1
            else:
                result["wrong"][name] = result["wrong"].get(name, 0) + 1
    finally:
        bus.shutdown()
    return result


# ------------------------------------------------------------------------------ polling
def poll(client: ModbusTcpClient, seconds: float, period: float = 0.01) -> np.ndarray:
    times, end = [], time.perf_counter() + seconds
    nxt = time.perf_counter()
    while time.perf_counter() < end:
        t0 = time.perf_counter()
        r = client.read_input_registers(0, count=10, device_id=IO.unit_id)
        if r.isError():
            raise RuntimeError(f"normal client got {r}")
        times.append(time.perf_counter() - t0)
        nxt += period
        time.sleep(max(0.0, nxt - time.perf_counter()))
    return np.array(times) * 1e3


def kill_during_recording(seconds: float) -> dict:
    port = free_port()
    with tempfile.TemporaryDirectory(prefix="soak_record_") as tmp:
        run = Path(tmp) / "run"
        gw = twin("serve", "house1", "--modbus-tcp", f"127.0.0.1:{port}", "--speed", "1",
                  "--record", str(run), stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        try:
            wait_port(port)
            line = gw.stdout.readline()
            while line and not line.startswith("serving"):
                line = gw.stdout.readline()
            started = time.monotonic()            # the clock starts just before "serving"
            time.sleep(seconds)
            gw.send_signal(signal.SIGKILL)
            elapsed = time.monotonic() - started
            gw.wait(10)
        finally:
            if gw.poll() is None:
                gw.kill()
        text = (run / "signals.csv").read_text()
        rows = [r for r in text.splitlines()[1:] if r]
        partial = bool(text) and not text.endswith("\n")
        complete = rows[:-1] if partial else rows
        last_t = float(complete[-1].split(",")[0]) if complete else 0.0
        return {"elapsed_s": elapsed, "last_t": last_t, "lost_s": max(0.0, elapsed - last_t),
                "rows": len(complete), "partial_last_row": partial}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=100_000)
    ap.add_argument("--sdo", type=int, default=10_000)
    ap.add_argument("--idle", type=int, default=1000)
    ap.add_argument("--poll-seconds", type=float, default=5.0)
    args = ap.parse_args()
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    want = min(hard, max(soft, 4 * args.idle + 256))
    resource.setrlimit(resource.RLIMIT_NOFILE, (want, hard))   # inherited by the gateway
    hub_port, mb_port = free_port(), free_port()
    log_dir = Path(tempfile.mkdtemp(prefix="soak_"))
    err_path = log_dir / "serve.stderr"
    hub = twin("can-hub", "--port", str(hub_port), "--quiet", stdout=subprocess.DEVNULL,
               stderr=subprocess.DEVNULL)
    err = err_path.open("w")
    gw = None
    try:
        wait_port(hub_port)
        gw = twin("serve", "house1", "--modbus-tcp", f"127.0.0.1:{mb_port}", "--speed", "1",
                  "--can", f"socketcand:127.0.0.1:{hub_port}:can0", "--record", str(log_dir / "run"),
                  "--max-connections", str(args.idle + 64), "--idle-timeout", "600",
                  stdout=subprocess.PIPE, stderr=err)
        wait_port(mb_port)
        time.sleep(1.0)
        client = ModbusTcpClient("127.0.0.1", port=mb_port, timeout=2.0)
        client.connect()
        poll(client, 1.0)                                                   # warm-up
        lines0 = len(err_path.read_text().splitlines())
        rss0 = rss_mb(gw.pid)
        before = poll(client, args.poll_seconds)

        t0 = time.monotonic()
        flood = malformed_flood(mb_port, args.frames, 300.0)
        flood_s = time.monotonic() - t0
        tried = sum(flood["sent"].values())
        lines1 = len(err_path.read_text().splitlines())
        alive1 = gw.poll() is None
        print(f"malformed: {tried} frames of {len(flood['sent'])} kinds in {flood['batches']} connections, "
              f"{flood_s:.1f} s; check reads wrong or missing: {flood['bad_checks']}; "
              f"log lines {lines1 - lines0}; gateway alive: {alive1}")

        t0 = time.monotonic()
        sdo_result = bad_sdo(hub_port, args.sdo, 300.0)
        print(f"SDO: {sdo_result['tried']} bad requests of {len(SDO_KINDS)} kinds in "
              f"{time.monotonic() - t0:.1f} s; right aborts {sdo_result['right']}, wrong "
              f"{sdo_result['wrong'] or 0}, no answer {sdo_result['missing'] or 0}; slowest "
              f"{sdo_result['slowest_ms']:.1f} ms")

        idle: list[socket.socket] = []
        refused = 0
        for _ in range(args.idle):
            s = socket.create_connection(("127.0.0.1", mb_port), timeout=2.0)
            idle.append(s)
        time.sleep(0.5)
        for s in idle:                      # a refused one reads EOF at once
            s.setblocking(False)
            try:
                if s.recv(1) == b"":
                    refused += 1
            except BlockingIOError:
                pass
        during = poll(client, args.poll_seconds)
        for s in idle:
            s.close()
        time.sleep(0.5)
        after = poll(client, args.poll_seconds)
        rss1 = rss_mb(gw.pid)
        alive = gw.poll() is None
        client.close()
        print(f"{args.idle} idle connections held ({refused} refused); normal client read(10) p99: "
              f"before {np.percentile(before, 99):.2f} ms, during {np.percentile(during, 99):.2f} ms, "
              f"after {np.percentile(after, 99):.2f} ms (medians {np.median(before):.2f} / "
              f"{np.median(during):.2f} / {np.median(after):.2f} ms)")
        print(f"gateway RSS {rss0:.1f} MB -> {rss1:.1f} MB")
        gw.send_signal(signal.SIGTERM)
        out = gw.communicate(timeout=60)[0]
        gw_returncode = gw.returncode
    finally:
        if gw is not None and gw.poll() is None:
            gw.kill()
        hub.terminate()
        hub.wait(10)
        err.close()
    stderr = err_path.read_text()
    lines_total = len(stderr.splitlines()) - lines0
    tracebacks = stderr.count("Traceback")
    audit = [line.strip() for line in out.splitlines() if "malformed frames from" in line or "link:" in line]
    counted = sum(int(m.group(1)) for m in re.finditer(r"malformed frames from \S+: (\d+)", out))
    print("gateway audit (malformed frames, connections):")
    print("\n".join("  " + line for line in audit))
    print(f"gateway log lines after the warm-up: {lines_total} (stderr {err_path}); tracebacks {tracebacks}; "
          f"exit code {gw_returncode}")
    killed = kill_during_recording(5.0)
    print(f"kill -9 after {killed['elapsed_s']:.1f} s at 1x: signals.csv ends at t={killed['last_t']:.0f} s "
          f"({killed['rows']} rows, partial last row: {killed['partial_last_row']}); "
          f"{killed['lost_s']:.1f} s of signals lost")
    crashes = int(not alive1) + int(not alive) + int(gw_returncode not in (0, None)) + tracebacks
    print(f"RESULT malformed_frames_tried={tried}")
    print(f"RESULT malformed_kinds={len(flood['sent'])}")
    print(f"RESULT malformed_frames_counted={counted}")
    print(f"RESULT log_lines_per_1000_malformed={1000 * lines_total / max(tried, 1):.3f}")
    print(f"RESULT sdo_tried={sdo_result['tried']}")
    print(f"RESULT sdo_right_aborts={sdo_result['right']}")
    print(f"RESULT sdo_wrong_aborts={sum(sdo_result['wrong'].values())}")
    print(f"RESULT sdo_missing_answers={sum(sdo_result['missing'].values())}")
    print(f"RESULT idle_connections={args.idle}")
    print(f"RESULT idle_refused={refused}")
    print(f"RESULT p99_before_ms={np.percentile(before, 99):.2f}")
    print(f"RESULT p99_during_ms={np.percentile(during, 99):.2f}")
    print(f"RESULT p99_after_ms={np.percentile(after, 99):.2f}")
    print(f"RESULT rss_growth_mb={rss1 - rss0:.1f}")
    print(f"RESULT kill9_seconds_lost={killed['lost_s']:.1f}")
    print(f"RESULT crashes={crashes}")


if __name__ == "__main__":
    main()
