"""Ports on this machine's loopback for servers the benchmarks and tools start themselves."""
from __future__ import annotations

import socket
import subprocess
import time


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
