"""Modbus TCP read latency of the gateway against a bare pymodbus server and a libmodbus C server.

Servers, each in its own process on loopback: the gateway (`twin serve house1 --speed 1`, the
plant stepping in real time) on asyncio's event loop and, if installed, on uvloop; a bare pymodbus
server (asyncio); a minimal libmodbus server (benchmarks/c/modbus_server.c, built here with gcc and
pkg-config). Two clients, each its own process: a pymodbus sync client and a libmodbus C client
(benchmarks/c/modbus_client.c). A client reads 10 input registers from every server in
interleaved rounds (round r: gateway, bare, C, ... with the first server rotating), so that the
machine's noise falls on all of them alike.

Where the processes run decides the figures (a loopback round trip within one CPU is a third of
one across two), so both pinnings are measured in the same run: "across CPUs" (client on CPU 0,
servers on CPU 1) and "same CPU" (all on CPU 0). Every (pinning, client) run is repeated; the
figures are the median of the repeat medians with their min-max, ratios are taken within a run.
Then 20 clients poll the gateway at 10 Hz each and the gateway's step lateness p99 is read from
its own report (target < 5 ms). docs/design.md (Gateway latency) explains the method.
Run: python benchmarks/gateway_latency.py [--rounds 2000] [--repeats 5] [--poll-seconds 20]
"""
import argparse
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
from pymodbus.client import ModbusTcpClient

from gateway.loopback import build_c_harness, free_port, pin, wait_port

HERE = Path(__file__).resolve().parent
UNIT, COUNT = 5, 10  # storage_io (unit 5) maps input registers 0..9 in house 1

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

#: The pymodbus client, same arguments and output as benchmarks/c/modbus_client.c.
PY_CLIENT = """
import sys, time
from pymodbus.client import ModbusTcpClient
rounds, warmup, count = map(int, sys.argv[1:4])
clients = []
for target in sys.argv[4:]:
    host, rest = target.rsplit(":", 1)
    port, unit = rest.split("/")
    c = ModbusTcpClient(host, port=int(port), timeout=2)
    if not c.connect():
        sys.exit(f"pymodbus client: {target}: cannot connect")
    clients.append((c, int(unit)))
n, line, out = len(clients), [0] * len(clients), []
clock = time.perf_counter_ns
for r in range(-warmup, rounds):
    for k in range(n):
        i = (r + k) % n
        c, unit = clients[i]
        t0 = clock()
        rr = c.read_input_registers(0, count=count, device_id=unit)
        line[i] = clock() - t0
        if rr.isError():
            sys.exit(f"pymodbus client: {sys.argv[4 + i]}: {rr}")
    if r >= 0:
        out.append(" ".join(map(str, line)))
print("\\n".join(out))
"""

CLIENTS = ("pymodbus", "C")


def run_client(kind: str, exe: dict, targets: list[str], rounds: int, cpu: int) -> np.ndarray:
    """One client process pinned to `cpu`: round-trip times in µs, shape (rounds, len(targets))."""
    warmup = max(50, rounds // 10)
    if kind == "C":
        cmd = [str(exe["modbus_client"]), "-n", str(COUNT), "-r", str(rounds), "-w", str(warmup), *targets]
    else:
        cmd = [sys.executable, "-c", PY_CLIENT, str(rounds), str(warmup), str(COUNT), *targets]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                       preexec_fn=lambda: os.sched_setaffinity(0, {cpu}))
    if p.returncode:
        raise RuntimeError(f"{kind} client failed: {p.stderr.strip()}")
    return np.array([line.split() for line in p.stdout.split("\n") if line], dtype=float).reshape(rounds, -1) / 1e3


def spread(values) -> str:
    v = np.asarray(values)
    return f"{np.median(v):7.3f} [{v.min():.3f}-{v.max():.3f}]" if v.max() < 20 else \
        f"{np.median(v):7.0f} [{v.min():.0f}-{v.max():.0f}]"


def latency(procs: dict, exe: dict, targets: list[str], rounds: int, repeats: int) -> dict:
    """medians[pinning][client][server] = list over repeats (µs); the runs are interleaved."""
    ncpu = len(os.sched_getaffinity(0))
    pinnings = {"across CPUs": (0, {1}), "same CPU": (0, {0})} if ncpu >= 2 else {"same CPU": (0, {0})}
    med = {p: {c: {s: [] for s in procs} for c in CLIENTS} for p in pinnings}
    for rep in range(repeats):
        for pname, (client_cpu, server_cpus) in pinnings.items():
            for proc in procs.values():
                pin(proc.pid, server_cpus)
            for client in CLIENTS:
                times = run_client(client, exe, targets, rounds, client_cpu)
                for j, server in enumerate(procs):
                    med[pname][client][server].append(float(np.median(times[:, j])))
        print(f"  repeat {rep + 1}/{repeats} done", flush=True)
    return med


def report(med: dict, rounds: int, repeats: int) -> dict:
    results = {}
    for pname, by_client in med.items():
        servers = list(by_client[CLIENTS[0]])
        gateways = [s for s in servers if s.startswith("gateway")]
        where = "client on CPU 0, servers on CPU 1" if pname == "across CPUs" else "client and servers on CPU 0"
        print(f"\n{pname} ({where}): read {COUNT} input registers, median of {repeats} repeats x "
              f"{rounds} rounds [min-max of the repeat medians], us")
        print(f"  {'server':28s}" + "".join(f"{c + ' client':>26s}" for c in CLIENTS))
        for s in servers:
            print(f"  {s:28s}" + "".join(f"{spread(by_client[c][s]):>26s}" for c in CLIENTS))
        pairs = [(g, "bare pymodbus") for g in gateways] + [(s, "C server") for s in servers if s != "C server"]
        for num, den in pairs:
            cells = []
            for c in CLIENTS:
                r = np.array(by_client[c][num]) / np.array(by_client[c][den])
                cells.append(f"{spread(r):>26s}")
                results[(pname, c, num, den)] = float(np.median(r))
            print(f"  {num + '/' + den:28s}" + "".join(cells))
        for c in CLIENTS:
            for s in servers:
                results[(pname, c, s)] = float(np.median(by_client[c][s]))
    return results


def poller(port: int, seconds: float, stop: threading.Event, count: list):
    c = ModbusTcpClient("127.0.0.1", port=port)
    c.connect()
    nxt = time.perf_counter()
    end = nxt + seconds
    while time.perf_counter() < end and not stop.is_set():
        c.read_input_registers(0, count=COUNT, device_id=UNIT)
        count[0] += 1
        nxt += 0.1
        time.sleep(max(0.0, nxt - time.perf_counter()))
    c.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=2000, help="timed rounds per client run (default 2000)")
    ap.add_argument("--repeats", type=int, default=5, help="runs per pinning and client (default 5)")
    ap.add_argument("--poll-seconds", type=float, default=20.0)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="gateway_latency_"))
    exe = build_c_harness(HERE / "c", tmp)
    loops = ["asyncio"] + (["uvloop"] if importlib.util.find_spec("uvloop") else [])
    if len(loops) == 1:
        print('uvloop is not installed (pip install -e ".[fast]"): the gateway runs on asyncio only')
    ports = {s: free_port() for s in [f"gateway {loop}" for loop in loops] + ["bare pymodbus", "C server"]}
    procs = {f"gateway {loop}": subprocess.Popen(
        [sys.executable, "-m", "cli.main", "serve", "house1", "--modbus-tcp",
         f"127.0.0.1:{ports[f'gateway {loop}']}", "--speed", "1", "--loop", loop],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) for loop in loops}
    procs["bare pymodbus"] = subprocess.Popen([sys.executable, "-c", BARE, str(ports["bare pymodbus"])])
    procs["C server"] = subprocess.Popen([str(exe["modbus_server"]), "127.0.0.1", str(ports["C server"]), "200"],
                                         stdout=subprocess.DEVNULL)
    default = f"gateway {loops[-1]}"  # what `twin serve` runs on here (--loop auto)
    try:
        for name, port in ports.items():
            wait_port(port, proc=procs[name])
        targets = [f"127.0.0.1:{ports[s]}/{UNIT}" for s in procs]
        for _ in range(60):  # every server answers one read before the timing starts
            if subprocess.run([str(exe["modbus_client"]), "-v", "-r", "0", *targets], capture_output=True).returncode == 0:
                break
            time.sleep(0.5)
        med = latency(procs, exe, targets, args.rounds, args.repeats)
        res = report(med, args.rounds, args.repeats)
        for proc in procs.values():
            pin(proc.pid, os.sched_getaffinity(0))
        stop, count = threading.Event(), [0]
        threads = [threading.Thread(target=poller, args=(ports[default], args.poll_seconds, stop, count))
                   for _ in range(20)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        print(f"\n20 clients polled the {default} at 10 Hz for {args.poll_seconds:g} s: {count[0]} requests")
    finally:
        for proc in procs.values():
            proc.terminate()
        shutil.rmtree(tmp, ignore_errors=True)
    out = {name: p.communicate(timeout=30)[0] for name, p in procs.items() if name.startswith("gateway")}
    m = re.search(r"step lateness: .*p99 ([0-9.]+) ms", out[default])
    p99 = float(m.group(1)) if m else float("nan")
    print(f"{default} step lateness p99 = {p99:.2f} ms (target < 5 ms)")
    pn = "across CPUs" if ("across CPUs", "C", "C server") in res else "same CPU"
    print(f"RESULT latency_ratio={res[(pn, 'pymodbus', 'gateway asyncio', 'bare pymodbus')]:.3f}")
    print(f"RESULT latency_ratio_c_client={res[(pn, 'C', 'gateway asyncio', 'bare pymodbus')]:.3f}")
    if "gateway uvloop" in procs:
        print(f"RESULT latency_ratio_uvloop={res[(pn, 'pymodbus', 'gateway uvloop', 'bare pymodbus')]:.3f}")
    for p, key in (("across CPUs", "across"), ("same CPU", "same_cpu")):
        if (p, "C", "C server") not in res:
            continue
        print(f"RESULT c_server_us_{key}={res[(p, 'C', 'C server')]:.1f}")
        for g in (s for s in procs if s.startswith("gateway")):
            loop = g.split()[1]
            print(f"RESULT gateway_{loop}_us_{key}={res[(p, 'C', g)]:.1f}")
            print(f"RESULT gateway_{loop}_vs_c_server_{key}={res[(p, 'C', g, 'C server')]:.3f}")
    print(f"RESULT lateness_p99_ms={p99:.2f}")


if __name__ == "__main__":
    main()
