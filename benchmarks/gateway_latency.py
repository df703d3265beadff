"""Modbus round trip of the gateway (plant running in real time) vs a bare pymodbus server.

Both servers run in their own process on loopback; one pymodbus sync client measures
read(10 input registers) and write(1 holding register) alternately against each, in the same
run, and the ratio gateway/bare is printed (target <= 1.10). Then 20 clients poll the gateway at
10 Hz each and the gateway's step lateness p99 is read from its own report (target < 5 ms).
Run: python benchmarks/gateway_latency.py [--n 2000] [--poll-seconds 20]
"""
import argparse
import re
import socket
import subprocess
import sys
import threading
import time

import numpy as np
from pymodbus.client import ModbusTcpClient

BARE = """
import asyncio, sys
from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice
def dev(i):
    regs = [SimData(0, count=200, values=215, datatype=DataType.REGISTERS)]
    bits = [SimData(0, count=16, values=False, datatype=DataType.BITS)]
    return SimDevice(id=i, simdata=(bits, bits, regs, regs))
async def main():
    server = ModbusTcpServer([dev(4), dev(5)], address=("127.0.0.1", int(sys.argv[1])))
    await server.serve_forever()
asyncio.run(main())
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_port(port: int, timeout: float = 60.0) -> None:
    end = time.time() + timeout
    while time.time() < end:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                return
        except OSError:
            time.sleep(0.1)
    raise RuntimeError(f"server on port {port} did not come up")


def measure(client, n: int):
    reads, writes = [], []
    for i in range(n):
        t0 = time.perf_counter()
        r = client.read_input_registers(0, count=10, device_id=5)
        t1 = time.perf_counter()
        w = client.write_register(103, 50 + i % 10, device_id=4)
        t2 = time.perf_counter()
        if r.isError() or w.isError():
            raise RuntimeError(f"request failed: {r} {w}")
        reads.append(t1 - t0)
        writes.append(t2 - t1)
    return np.array(reads), np.array(writes)


def poller(port: int, seconds: float, stop: threading.Event, count: list):
    c = ModbusTcpClient("127.0.0.1", port=port)
    c.connect()
    nxt = time.perf_counter()
    end = nxt + seconds
    while time.perf_counter() < end and not stop.is_set():
        c.read_input_registers(0, count=10, device_id=5)
        count[0] += 1
        nxt += 0.1
        time.sleep(max(0.0, nxt - time.perf_counter()))
    c.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--poll-seconds", type=float, default=20.0)
    args = ap.parse_args()
    gp, bp = free_port(), free_port()
    gw = subprocess.Popen([sys.executable, "-m", "gateway.cli.main", "serve", "house1", "--modbus-tcp",
                           f"127.0.0.1:{gp}", "--speed", "1"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True)
    bare = subprocess.Popen([sys.executable, "-c", BARE, str(bp)])
    try:
        wait_port(gp)
        wait_port(bp)
        cg, cb = ModbusTcpClient("127.0.0.1", port=gp), ModbusTcpClient("127.0.0.1", port=bp)
        cg.connect()
        cb.connect()
        measure(cg, 100)
        measure(cb, 100)  # warm-up
        res = {"gateway": ([], []), "bare": ([], [])}
        for _ in range(10):  # interleaved blocks: machine noise hits both alike
            for name, c in (("gateway", cg), ("bare", cb)):
                r, w = measure(c, args.n // 10)
                res[name][0].append(r)
                res[name][1].append(w)
        stats = {}
        for name, (r, w) in res.items():
            r, w = np.concatenate(r) * 1e6, np.concatenate(w) * 1e6
            stats[name] = (np.median(r), np.percentile(r, 99), np.median(w), np.percentile(w, 99))
            print(f"{name:8s} read(10): median {stats[name][0]:7.0f} us  p99 {stats[name][1]:7.0f} us | "
                  f"write(1): median {stats[name][2]:7.0f} us  p99 {stats[name][3]:7.0f} us")
        cg.close()
        cb.close()
        ratio = (stats["gateway"][0] + stats["gateway"][2]) / (stats["bare"][0] + stats["bare"][2])
        print(f"median round-trip ratio gateway/bare = {ratio:.3f} (target <= 1.10)")
        stop, count = threading.Event(), [0]
        threads = [threading.Thread(target=poller, args=(gp, args.poll_seconds, stop, count)) for _ in range(20)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        print(f"20 clients polled at 10 Hz for {args.poll_seconds:g} s: {count[0]} requests")
    finally:
        bare.terminate()
        gw.terminate()
    out = gw.communicate(timeout=30)[0]
    m = re.search(r"p99 ([0-9.]+) ms", out)
    p99 = float(m.group(1)) if m else float("nan")
    print(f"gateway step lateness p99 = {p99:.2f} ms (target < 5 ms); its report:")
    print("\n".join("  " + line for line in out.strip().splitlines()[-6:]))
    print(f"RESULT latency_ratio={ratio:.3f}")
    print(f"RESULT lateness_p99_ms={p99:.2f}")


if __name__ == "__main__":
    main()
