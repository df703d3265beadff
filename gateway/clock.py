"""Clocks that advance the plant: lock-step (explicit steps) and paced (real time x factor).

The clock is the only code that reads wall time. A paced clock counts lateness (how far behind
its schedule a step started) instead of raising; the runtime reports it.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np


class LockStepClock:
    """The plant advances only when step() is called: deterministic tests and co-simulation."""

    mode = "lock-step"

    def __init__(self, dt: float = 1.0):
        if not dt > 0:
            raise ValueError(f"lock-step clock: dt = {dt}; must be positive")
        self.dt = dt
        self._tick: Callable[[float], None] | None = None

    def bind(self, tick: Callable[[float], None]) -> None:
        self._tick = tick

    def step(self, n: int = 1) -> None:
        for _ in range(n):
            self._tick(self.dt)

    def start(self) -> None:
        pass

    def stop(self) -> None:
        pass

    def lateness(self) -> np.ndarray:
        return np.zeros(0)


class PacedClock:
    """Steps the plant by dt of simulated time every dt/factor seconds of wall time, in a thread.

    factor 1 is real time, N is N x accelerated. Lateness of each step (wall time behind the
    schedule) is kept in a ring of the last 100,000 steps. A run that falls behind does not try
    to catch up by bursting: it restarts its schedule from now and counts the lateness.
    """

    mode = "paced"

    def __init__(self, factor: float = 1.0, dt: float = 1.0):
        if not factor > 0 or not dt > 0:
            raise ValueError(f"paced clock: factor = {factor}, dt = {dt}; both must be positive")
        self.factor = factor
        self.dt = dt
        self._tick: Callable[[float], None] | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._late = np.zeros(100_000)
        self._n = 0

    def bind(self, tick: Callable[[float], None]) -> None:
        self._tick = tick

    def start(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="plant-clock", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread:
            self._thread.join(timeout=5)

    def _run(self) -> None:
        period = self.dt / self.factor
        due = time.perf_counter() + period
        while not self._stop.is_set():
            wait = due - time.perf_counter()
            if wait > 0:
                if self._stop.wait(wait):
                    break
            now = time.perf_counter()
            self._late[self._n % self._late.shape[0]] = max(0.0, now - due)
            self._n += 1
            self._tick(self.dt)
            due += period
            if time.perf_counter() - due > 10 * period:  # far behind: restart the schedule
                due = time.perf_counter() + period

    def lateness(self) -> np.ndarray:
        """Lateness [s] of the recorded steps."""
        n = min(self._n, self._late.shape[0])
        return self._late[:n].copy()
