"""`twin ARGV` as a process forked from this one: a harness that starts many twin processes (benches,
twins) in seconds, once the caller has imported and compiled what they need, instead of each
importing numba, pymodbus and the twin afresh (2-3 s of CPU each). Linux and macOS (fork)."""
from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import threading

FORK = multiprocessing.get_context("fork")


def _twin_main(argv: list[str], out: int) -> None:
    os.dup2(out, 1)
    os.dup2(out, 2)
    sys.stdout = open(1, "w", buffering=1, closefd=False)
    sys.stderr = sys.stdout
    from cli.main import main

    code = main(argv)
    sys.stdout.flush()
    os._exit(code)


class Twin:
    """`twin ARGV` (cli.main) as its own process, forked from this one: the same
    code as `python -m cli.main ARGV`, its output (stdout and stderr) read here. The subset of
    subprocess.Popen the benchmark uses."""

    def __init__(self, argv: list[str]) -> None:
        sys.stdout.flush()
        read, write = os.pipe()
        self.process = FORK.Process(target=_twin_main, args=(argv, write))
        self.process.start()
        os.close(write)
        self.stdout = os.fdopen(read, "r")
        self.rest: list[str] = []
        self.reader: threading.Thread | None = None

    def poll(self) -> int | None:
        return self.process.exitcode

    def send_signal(self, sig: int) -> None:
        if self.process.exitcode is None:
            os.kill(self.process.pid, sig)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)

    def communicate(self, timeout: float) -> tuple[str, None]:
        """Wait for the end (raises subprocess.TimeoutExpired) and return what it printed since."""
        if self.reader is None:
            self.reader = threading.Thread(target=lambda: self.rest.extend(self.stdout), daemon=True)
            self.reader.start()
        self.process.join(timeout)
        if self.process.exitcode is None:
            raise subprocess.TimeoutExpired(str(self.process.pid), timeout)
        self.reader.join(5.0)
        return "".join(self.rest), None
