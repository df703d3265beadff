"""Servers the benchmarks and tools start themselves on this machine's loopback: free ports, waiting
for a listener, the libmodbus C server and client they measure against, and pinning a server's
threads to CPUs."""
from __future__ import annotations

import os
import shutil
import socket
import subprocess
import time
from pathlib import Path


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port nothing listens on now (the OS's choice)."""
    with socket.socket() as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def wait_port(port: int, timeout: float = 60.0, proc: subprocess.Popen | None = None,
              host: str = "127.0.0.1") -> None:
    """Until something accepts connections on port; a RuntimeError after timeout, or at once when
    the server process proc has exited (with the end of what it printed)."""
    end = time.time() + timeout
    while time.time() < end:
        if proc is not None and proc.poll() is not None:
            out = proc.communicate()[0] if proc.stdout else ""
            raise RuntimeError(f"server for port {port} exited with {proc.returncode}: {(out or '').strip()[-2000:]}")
        try:
            with socket.create_connection((host, port), timeout=0.5):
                return
        except OSError:
            time.sleep(0.1)
    raise RuntimeError(f"nothing listens on port {port} after {timeout:g} s")


def build_c_harness(sources: Path, out: Path) -> dict[str, Path]:
    """gcc + pkg-config libmodbus: modbus_server and modbus_client from `sources` (benchmarks/c),
    built into `out`; SystemExit naming the package when a tool is missing."""
    if shutil.which("gcc") is None or shutil.which("pkg-config") is None:
        raise SystemExit("libmodbus C harness: needs gcc and pkg-config; apt-get install -y gcc pkg-config libmodbus-dev")
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "libmodbus"], capture_output=True, text=True)
    if flags.returncode:
        raise SystemExit("libmodbus C harness: libmodbus not found by pkg-config; apt-get install -y libmodbus-dev")
    exe = {}
    for name in ("modbus_server", "modbus_client"):
        exe[name] = out / name
        subprocess.run(["gcc", "-O2", "-std=c99", "-D_POSIX_C_SOURCE=200809L", "-Wall", "-Wextra", "-Werror",
                        "-o", str(exe[name]), str(sources / f"{name}.c"), *flags.stdout.split()], check=True)
    return exe


def pin(pid: int, cpus: set[int]) -> None:
    """Every thread of process `pid` onto `cpus` (like `taskset -a -p`)."""
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            os.sched_setaffinity(int(tid), cpus)
        except ProcessLookupError:  # a thread that just ended
            pass
