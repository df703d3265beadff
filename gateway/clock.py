"""Clocks that advance the plant: lock-step (explicit steps) and paced (real time x factor).

The clock is the only code that reads wall time. A paced clock counts lateness (how far behind
its schedule a step started) instead of raising; the runtime reports it.
"""
from __future__ import annotations

import math
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
    to catch up by bursting: it restarts its schedule at its next slot and counts the lateness.
    What it does with the slots it missed: by default they are dropped (the simulated time falls
    behind the wall clock; a controller under test sees a pause). `catch_up=True` gives them to
    the next step instead (one step of dt x (1 + missed)): the simulated time stays locked to
    the wall clock x factor, as PHIL needs, where real benches keep running while the twin
    stalls and the heat they delivered in the meantime belongs to the model's span.

    `phase` (s, 0 <= phase < dt/factor) puts the steps at that offset within the cycle of the
    system clock (at 1 s cycles, phase 0.2 steps at every whole second + 0.2 s), so processes
    started together can step at phases of their own instead of all at once; None (the default)
    steps one cycle after start().
    """

    mode = "paced"

    def __init__(self, factor: float = 1.0, dt: float = 1.0, phase: float | None = None,
                 catch_up: bool = False):
        if not factor > 0 or not dt > 0:
            raise ValueError(f"paced clock: factor = {factor}, dt = {dt}; both must be positive")
        if phase is not None and not 0.0 <= phase < dt / factor:
            raise ValueError(f"paced clock: phase = {phase} s; must be 0 ... {dt / factor:g} s (one cycle)")
        self.factor = factor
        self.dt = dt
        self.phase = phase
        self.catch_up = catch_up
        self.missed = 0                     # slots missed (dropped, or caught up with catch_up)
        self._tick: Callable[[float], None] | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._late = np.zeros(100_000)
        self._start = np.zeros(100_000)     # each step's start, perf_counter s
        self._wall_offset = 0.0             # system clock - perf_counter, read once at start()
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

    def _first_due(self, period: float) -> float:
        """perf_counter() time of the first step: one cycle from now, or the next slot at `phase`
        within the system clock's cycle (read once: the schedule then runs on perf_counter)."""
        now = time.perf_counter()
        wall = time.time()
        self._wall_offset = wall - now
        if self.phase is None:
            return now + period
        slot = (math.floor((wall - self.phase) / period) + 1) * period + self.phase
        return now + (slot - wall)

    def _run(self) -> None:
        period = self.dt / self.factor
        due = self._first_due(period)
        owed = 0                            # missed slots the next step makes up (catch_up)
        while not self._stop.is_set():
            wait = due - time.perf_counter()
            if wait > 0:
                if self._stop.wait(wait):
                    break
            now = time.perf_counter()
            self._late[self._n % self._late.shape[0]] = max(0.0, now - due)
            self._start[self._n % self._start.shape[0]] = now
            self._n += 1
            self._tick(self.dt * (1 + owed))
            owed = 0
            due += period
            behind = time.perf_counter() - due
            if behind > 10 * period:  # far behind: restart the schedule at its next slot (same phase)
                missed = math.ceil(behind / period)
                due += missed * period
                self.missed += missed
                owed = missed if self.catch_up else 0

    def lateness(self) -> np.ndarray:
        """Lateness [s] of the recorded steps."""
        n = min(self._n, self._late.shape[0])
        return self._late[:n].copy()

    def phases(self) -> np.ndarray:
        """Where in the system clock's cycle each recorded step started [s, 0 ... dt/factor]: the
        phase actually kept (with `phase` set, that phase plus the step's lateness)."""
        n = min(self._n, self._start.shape[0])
        return np.mod(self._start[:n] + self._wall_offset, self.dt / self.factor)
