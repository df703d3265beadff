"""Pipelined Modbus TCP requests: several frames in one TCP segment, each answered with its own id.

The Modbus TCP spec lets a master send a request before the answer to the previous one has come
(the MBAP length field delimits each frame), so frames arrive coalesced in one segment. This
starts `twin serve house1 --modbus-tcp` on loopback and sends N frames as triples, each triple in
one `sendall` (FC3 boiler 449..450, FC4 storage I/O 0..9, FC3 boiler 198; transaction ids counting
up), and counts the answers whose transaction id, function code and length match the request. The
comparison, in the same run against the same server: the same frames, one per segment, each sent
after the previous answer. A triple whose answers do not all come within `--timeout` s of the last
one received counts what came.

Prints answered/sent for both and `RESULT pipelined_answered_pct=...`.
Run: python benchmarks/modbus_pipelining.py [--frames 30000] [--timeout 0.05] [--seconds 300]
"""
import argparse
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

from gateway.loopback import free_port, wait_port

REPO = Path(__file__).resolve().parents[1]

#: (unit, function, address, count): registers house 1 maps (boiler unit 2, storage I/O unit 5)
TRIPLE = ((2, 3, 449, 2), (5, 4, 0, 10), (2, 3, 198, 1))


def request(tid: int, unit: int, fc: int, address: int, count: int) -> bytes:
    return struct.pack(">HHHBBHH", tid, 0, 6, unit, fc, address, count)


class Reader:
    """MBAP frames off one connection, by transaction id."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock, self.buffer = sock, b""

    def collect(self, expected: dict[int, tuple[int, int]], timeout: float) -> int:
        """Answers received for `expected` {tid: (fc, count)} until all came or none for `timeout` s."""
        good, pending = 0, dict(expected)
        self.sock.settimeout(timeout)
        while pending:
            while len(self.buffer) >= 6 and len(self.buffer) >= 6 + struct.unpack(">H", self.buffer[4:6])[0]:
                size = 6 + struct.unpack(">H", self.buffer[4:6])[0]
                frame, self.buffer = self.buffer[:size], self.buffer[size:]
                tid = struct.unpack(">H", frame[:2])[0]
                want = pending.pop(tid, None)
                if want is not None and frame[7] == want[0] and len(frame) == 9 + 2 * want[1]:
                    good += 1
            if not pending:
                break
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                break
            if not chunk:
                break
            self.buffer += chunk
        return good


def connect(port: int) -> socket.socket:
    s = socket.create_connection(("127.0.0.1", port), timeout=2.0)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def run(port: int, frames: int, pipelined: bool, timeout: float, seconds: float) -> tuple[int, int, float]:
    """(answered, sent, wall seconds)."""
    sent = answered = 0
    tid = 0
    t0 = time.perf_counter()
    with connect(port) as s:
        reader = Reader(s)
        while sent + len(TRIPLE) <= frames and time.perf_counter() - t0 < seconds:
            batch, expected = [], {}
            for unit, fc, address, count in TRIPLE:
                tid = tid % 0xFFFF + 1
                batch.append(request(tid, unit, fc, address, count))
                expected[tid] = (fc, count)
            if pipelined:
                s.sendall(b"".join(batch))
                answered += reader.collect(expected, timeout)
            else:
                for frame, (t, want) in zip(batch, expected.items()):
                    s.sendall(frame)
                    answered += reader.collect({t: want}, timeout)
            sent += len(batch)
    return answered, sent, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=30_000, help="frames per mode (multiple of 3)")
    ap.add_argument("--timeout", type=float, default=0.05, help="s to wait for a missing answer")
    ap.add_argument("--seconds", type=float, default=300.0, help="time bound per mode")
    args = ap.parse_args()
    port = free_port()
    server = subprocess.Popen([sys.executable, "-m", "cli.main", "serve", "house1", "--modbus-tcp",
                               f"127.0.0.1:{port}", "--speed", "1"], cwd=REPO, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)
    try:
        wait_port(port)
        results = {}
        for mode, pipelined in (("one frame per segment", False), ("pipelined triples", True)):
            answered, sent, wall = run(port, args.frames, pipelined, args.timeout, args.seconds)
            results[mode] = (answered, sent)
            print(f"{mode:24s}: answered {answered}/{sent} ({100 * answered / max(sent, 1):.2f} %), "
                  f"{wall:.1f} s, {sent / wall:,.0f} frames/s")
        alive = server.poll() is None
        print(f"server alive after both runs: {alive}")
    finally:
        server.terminate()
        try:
            server.wait(10)
        except subprocess.TimeoutExpired:
            server.kill()
    a, n = results["pipelined triples"]
    b, m = results["one frame per segment"]
    print(f"RESULT pipelined_answered_pct={100 * a / max(n, 1):.2f}")
    print(f"RESULT sequential_answered_pct={100 * b / max(m, 1):.2f}")


if __name__ == "__main__":
    main()
