"""BenchPlc: a bench emulator as the bench PLC that polls the twin (the twin serves it,
phil/served.py): every `period` s of wall time it reads the set-points from the twin and writes
what its sensors read, on the served map's registers; between polls its model runs on its own
real-time (or accelerated) clock, as in BenchServer.

Without an answer from the twin for the bench map's watchdog time (60 s if none) the PLC falls
back to its safe inputs, as the served bench does when the twin stops writing.
"""
from __future__ import annotations

import math
import threading
import time
from typing import Any

from gateway.maps import codec
from phil.benchmap import load_bench_map
from phil.emulator.model import read_params
from phil.emulator.server import make_model
from phil.master import ExchangeError, PlcLink
from phil.served import served_map


class BenchPlc:
    def __init__(self, name: str, host: str, port: int, speed: float = 1.0, period: float = 0.05,
                 seed: int = 0, params: dict[str, float] | None = None, timeout: float = 0.5) -> None:
        self.name = name
        self.model = make_model(name, seed, params)
        self.map = load_bench_map(read_params(name).get("bench", {}).get("map", name))
        self.link = PlcLink(served_map(self.map), host, port, timeout, retries=0)
        self.speed, self.period = speed, period
        self.watchdog_s = self.map.dmap.watchdog.timeout_s if self.map.dmap.watchdog else 60.0
        self.lock = threading.Lock()
        self.polls = self.failures = 0
        self.last_error = ""
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._pace, name=f"plc-{name}-model", daemon=True),
                         threading.Thread(target=self._poll, name=f"plc-{name}-poll", daemon=True)]

    def start(self) -> "BenchPlc":
        for t in self._threads:
            t.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(5)
        self.link.close()

    def _pace(self) -> None:
        wall0, h = time.monotonic(), self.model.h
        while not self._stop.is_set():
            target = (time.monotonic() - wall0) * self.speed
            with self.lock:
                while self.model.t + h <= target:
                    self.model.step(h)
            self._stop.wait(min(0.01, max(h / self.speed, 0.0005)))

    def _poll(self) -> None:
        last_ok = time.monotonic()
        while not self._stop.wait(self.period):
            try:
                setpoints = self.link.read()
                with self.lock:
                    for i in self.map.setpoints():
                        p = self.map.dmap.point(i.name)
                        if not math.isnan(setpoints[i.name]):
                            self.model.set(p.command, codec.to_si(p, setpoints[i.name]))
                    readings = {i.name: codec.to_device(self.map.dmap.point(i.name),
                                                        self.model.get(self.map.dmap.point(i.name).signal))
                                for i in self.map.measurements()}
                self.link.write(readings)
                self.polls += 1
                last_ok = time.monotonic()
            except ExchangeError as exc:
                self.failures += 1
                self.last_error = str(exc)
                if time.monotonic() - last_ok > self.watchdog_s:
                    with self.lock:
                        for name in self.model.INPUTS:
                            self.model.release(name)

    def summary(self) -> dict[str, Any]:
        with self.lock:
            return {"bench": self.name, "t": self.model.t, "ledger": self.model.balance(),
                    "inputs": dict(self.model.inputs), "polls": self.polls, "failures": self.failures,
                    "last_error": self.last_error}
