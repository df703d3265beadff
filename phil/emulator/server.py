"""BenchServer: one bench emulator served over Modbus TCP (or as a CANopen node) as its bench map
describes, on its own real-time (or accelerated) clock.

The bus face is the gateway's: the bench map's DeviceMap, a gateway Device over the bench model
(through a PlantPort) and the gateway's Modbus TCP transport. So writes are validated as on any
emulated device (range -> exception 03, a measured value is read-only -> 02), the map's watchdog
hands the set-points back to the bench's safe values when the twin falls silent, and a failing
bench answers exception 04 (`fail()`, for tests and `twin bench --fail-at`).

With `can=BUS` the same Device is the gateway's CANopen node instead (gateway/transports/
canopen_node.py), its object dictionary and PDOs built from the bench map (phil/pdo_layout.py):
set-points arrive in its RPDOs and go through the same validation and watchdog; its TPDOs
carry the measurements.
"""
from __future__ import annotations

import threading
import time
from typing import Any

from gateway.device.device import Device
from gateway.device.plant_port import PlantPort
from gateway.device.refusal import Refusal
from gateway.transports.canopen_node import CanopenTransport
from gateway.transports.modbus_tcp import ModbusTcpTransport
from phil.benchmap import BenchMap, load_bench_map
from phil.emulator.brine import BrineBench
from phil.emulator.grid import GridBench
from phil.emulator.model import BenchModel, read_params
from phil.emulator.solar import SolarBench
from phil.emulator.space_heating import SpaceHeatingBench
from phil.emulator.tap_water import TapWaterBench
from phil.pdo_layout import canopen_map
from plant.errors import ConfigError

MODELS: dict[str, type[BenchModel]] = {
    "space_heating": SpaceHeatingBench, "tap_water": TapWaterBench, "solar": SolarBench,
    "brine": BrineBench, "grid": GridBench}


class BenchDevice(Device):
    """A Device that can be told to fail: every request is then answered with exception 04."""

    failing = False

    def read_registers(self, table: str, address: int, count: int) -> list[int] | Refusal:
        if self.failing:
            return Refusal("failure", f"{self.id}: bench PLC fault")
        return super().read_registers(table, address, count)

    def write_registers(self, table: str, address: int, words: list[int], client: str = "",
                        transport: str = "") -> Refusal | None:
        if self.failing:
            return Refusal("failure", f"{self.id}: bench PLC fault")
        return super().write_registers(table, address, words, client, transport)


def make_model(name: str, seed: int = 0, params: dict[str, float] | None = None) -> BenchModel:
    """The bench model of phil/benches/<name>.toml (its [bench] kind), parameters overridden."""
    doc = read_params(name)
    kind = doc.get("bench", {}).get("kind", name)
    if kind not in MODELS:
        raise ConfigError(f"{doc['path']} [bench] kind = {kind!r}: must be one of {', '.join(MODELS)}")
    if params:
        doc = {**doc, "params": {**doc.get("params", {}), **params}}
    return MODELS[kind](doc, seed)


class BenchServer:
    """A bench model on its own clock, served on Modbus TCP at host:port (0 = a free port), or
    with `can` as a CANopen node on that python-can bus ("virtual:lab", "socketcand:...")."""

    def __init__(self, name: str, host: str = "127.0.0.1", port: int = 0, speed: float = 1.0,
                 seed: int = 0, params: dict[str, float] | None = None,
                 bench_map: BenchMap | None = None, can: str | None = None) -> None:
        self.name = name
        self.model = make_model(name, seed, params)
        doc = read_params(name)
        self.map = bench_map or load_bench_map(doc.get("bench", {}).get("map", name))
        self.port_lock = PlantPort(self.model)
        if can:
            self.map = canopen_map(self.map)
            self.device = BenchDevice(self.map.dmap, self.port_lock)
            self.transport = CanopenTransport([self.device], bus=can)
        else:
            self.device = BenchDevice(self.map.dmap, self.port_lock)
            self.transport = ModbusTcpTransport([self.device], host=host, port=port, idle_timeout=0)
        self.speed = speed
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"bench-{name}", daemon=True)

    @property
    def port(self) -> int | None:
        return getattr(self.transport, "port", None)

    def start(self) -> "BenchServer":
        self.transport.start()
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5)
        self.transport.stop()

    def fail(self, on: bool = True) -> None:
        self.device.failing = on

    def _run(self) -> None:
        """Pace the model: simulated time = wall time since start x speed, in model steps.

        The device's tick runs after the plant lock is released: the server thread takes the
        device's lock, then the plant's (Device.read_registers reads port.t and the signals), so
        ticking inside the plant lock took them the other way round and could deadlock the bench
        (its server stopped answering and accepting, and it did not stop on SIGTERM).

        It sleeps until the next model step is due: nothing changes before then (the watchdog
        counts the model's time too). Waking every 10 ms instead cost fifteen idle benches 8.6 %
        of a core in 1,500 wake-ups a second, each taking the GIL from the bench's server thread."""
        wall0, h = time.monotonic(), self.model.h
        while not self._stop.is_set():
            target = (time.monotonic() - wall0) * self.speed
            with self.port_lock.lock:
                while self.model.t + h <= target:
                    self.model.step(h)
                t = self.model.t
            self.device.tick(t)
            self._stop.wait(max(wall0 + (t + h) / self.speed - time.monotonic(), 0.0005))

    def summary(self) -> dict[str, Any]:
        with self.port_lock.lock:
            return {"bench": self.name, "t": self.model.t, "ledger": self.model.balance(),
                    "inputs": dict(self.model.inputs)}
