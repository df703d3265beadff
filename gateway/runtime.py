"""Runtime: plant + devices + transports + clock + recorder + audit, started and stopped together.

    rt = Runtime(load_house("house1", controller="external"), clock=LockStepClock(1.0),
                 record="runs/today")
    rt.add("modbus-tcp", host="127.0.0.1", port=0); rt.add("canopen", bus="virtual:house1")
    with rt:                      # starts transports and the clock
        rt.clock.step(60)         # lock-step: 60 plant steps of 1 s (devices tick, recorder writes)
    print(rt.audit.text())

Data flows one way: the clock steps the plant, devices read the plant through their PlantPort,
transports serve devices; commands come back only through a Device's validation.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from gateway.audit import Audit
from gateway.clock import LockStepClock, PacedClock
from gateway.device.device import Device
from gateway.device.plant_port import PlantPort
from gateway.maps.loader import load_all
from gateway.transports.base import Transport
from gateway.transports.registry import transport_class
from plant.errors import ConfigError
from profiles.recording import Recorder


class Runtime:
    def __init__(self, house, *, clock: LockStepClock | PacedClock | None = None,
                 devices: list[str] | None = None, record: str | Path | None = None,
                 record_interval: float = 1.0, read_only: bool = False, devices_dir: Path | None = None):
        self.house = house
        self.port = PlantPort(house)
        self.clock = clock or LockStepClock(1.0)
        self.clock.bind(self.tick)
        self.audit = Audit()
        maps = {k: m for k, m in load_all(devices_dir).items() if house.name in m.house.split("/")
                or m.house == house.name}
        if devices is not None:
            unknown = [d for d in devices if d not in maps]
            if unknown:
                raise ConfigError(f"devices {unknown}: not maps of {house.name}; available: {', '.join(sorted(maps))}")
            maps = {k: maps[k] for k in devices}
        self.recorder = None
        if record:
            self.recorder = Recorder(record, house.catalogue.names, {
                "house": house.name, "start": house.start, "clock": self.clock.mode,
                "dt": self.clock.dt, "factor": getattr(self.clock, "factor", None),
                "devices": {k: str(m.path) for k, m in maps.items()}}, interval=record_interval)
        self.devices = {k: Device(m, self.port, now=lambda: self.port.t, read_only=read_only)
                        for k, m in sorted(maps.items())}
        for d in self.devices.values():
            d.subscribe(self.event)
        self.transports: list[Transport] = []
        self.step_wall: list[float] = []
        self.pending_faults: list = []  # gateway.faults.Fault, sorted by time

    def schedule(self, faults) -> None:
        self.pending_faults = sorted([*self.pending_faults, *faults], key=lambda f: f.at)

    # --- wiring ------------------------------------------------------------------------------
    def event(self, ev: dict) -> None:
        """Record a device or transport event (audit, and events.csv when recording)."""
        ev.setdefault("t", self.port.t)
        self.audit.event(ev)
        if self.recorder:
            self.recorder.event(ev)

    def add(self, name: str, **options) -> Transport:
        """Serve the devices over the transport registered as `name` (gateway/transports/
        registry.py: "modbus-tcp", "modbus-rtu", "canopen") with its constructor's options, e.g.
        add("modbus-tcp", host="127.0.0.1", port=0), add("canopen", bus="virtual:house1")."""
        cls = transport_class(name)
        tr = cls(self.devices.values(), **{**cls.hooks(self), **options})
        self.transports.append(tr)
        return tr

    # --- time --------------------------------------------------------------------------------
    def tick(self, dt: float) -> None:
        """One clock step: plant, device logic (watchdogs), recording."""
        w0 = time.perf_counter()
        with self.port.lock:
            self.house.step(dt)
            t = self.house.t
            values = self.house.values()
        while self.pending_faults and self.pending_faults[0].at <= t + 1e-9:
            self.pending_faults.pop(0).apply(self.devices, self.transports)
        for d in self.devices.values():
            d.tick(t)
        for tr in self.transports:
            tr.wake()
        if self.recorder:
            self.recorder.signals(t, values)
        self.step_wall.append(time.perf_counter() - w0)

    def start(self) -> None:
        for tr in self.transports:
            tr.start()
        self.clock.start()

    def stop(self) -> dict:
        self.clock.stop()
        for tr in reversed(self.transports):
            tr.stop()
        report = {"audit": self.audit.report(), "lateness": self.lateness_summary()}
        if self.recorder:
            self.recorder.event({"t": self.port.t, "kind": "audit", "detail_json": report})
            self.recorder.close({"audit": report["audit"], "lateness": report["lateness"]})
        return report

    def lateness_summary(self) -> dict:
        late = self.clock.lateness()
        if late.size == 0:
            return {"steps": 0}
        return {"steps": int(late.size), "median_ms": float(np.median(late) * 1e3),
                "p99_ms": float(np.percentile(late, 99) * 1e3), "max_ms": float(late.max() * 1e3)}

    def __enter__(self) -> "Runtime":
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
