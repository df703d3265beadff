"""The twin as Modbus TCP server of a bench PLC: the second exchange direction of PHIL.

Here the bench PLC is the master: it reads the set-points from the twin and writes its
measurements to the twin, on its own cycle. The bus face is the gateway's (gateway/transports/
modbus_tcp.py and gateway/device/device.py, unchanged), serving a map derived from the bench
map (`served_map`):

  set-points    the bench map's holding registers, same addresses, read-only for the PLC
                (a write is refused with exception 02): it reads them with FC3
  measurements  holding registers at [phil] serve_offset + the bench map's input address, same
                type and scale, written by the PLC with FC16 (or FC6); no range check on the
                bus, the twin's guard judges them (NaN, out of range, wrong unit, silent)

`ServedLink` has BenchLink's face (exchange, write, close, last_exchange_s), so the loop is the
same in both directions: `exchange` publishes the set-points (device units) and returns the
measurements the PLC last wrote; a measurement the PLC has not written for `max_age_s` (wall)
is returned with no value and the reason (`silent`), which the guard holds and flags like a
failed poll. Several benches served on one HOST:PORT share one server (one unit id each).
"""
from __future__ import annotations

import dataclasses
import math
import threading
import time

from gateway.device.device import Device
from gateway.device.plant_port import PlantPort
from gateway.maps import codec
from gateway.maps.model import Point
from gateway.transports.modbus_tcp import ModbusTcpTransport
from phil.benchmap import BenchMap

def served_address(bench: BenchMap, point: Point) -> int:
    return bench.serve_offset + point.address


def served_map(bench: BenchMap) -> BenchMap:
    """The bench map as the twin serves it to the bench PLC (see the module text)."""
    points: list[Point] = []
    for i in bench.setpoints():
        p = bench.dmap.point(i.name)
        points.append(dataclasses.replace(p, access="R", command=None, signal=f"set.{p.name}",
                                          default=None))
    for i in bench.measurements():
        p = bench.dmap.point(i.name)
        points.append(dataclasses.replace(p, table="holding", address=served_address(bench, p),
                                          access="RW", signal=None, command=f"meas.{p.name}",
                                          range=None, default=None))
    functions = bench.dmap.functions | {3, 6, 16}
    dmap = dataclasses.replace(bench.dmap, points=tuple(points), watchdog=None, functions=functions,
                               _by_name={})
    return dataclasses.replace(bench, dmap=dmap)


class Board:
    """What the served Device reads and writes (the PlantPort face, SI values): the set-points
    the loop publishes and the measurements the PLC wrote, with the wall time of each write."""

    def __init__(self, bench: BenchMap, served: BenchMap) -> None:
        self.t = 0.0
        self.values: dict[str, float] = {}
        self.written: dict[str, float] = {}
        for i in bench.setpoints():         # served before the first publish: the safe values
            self.values[f"set.{i.name}"] = codec.to_si(bench.dmap.point(i.name), i.safe)
        for i in bench.measurements():
            self.values[f"meas.{i.name}"] = math.nan
        self.catalogue = frozenset(self.values)

    def get(self, name: str) -> float:
        return self.values[name]

    def set(self, name: str, value: float) -> None:
        self.values[name] = float(value)
        self.written[name] = time.monotonic()

    def release(self, name: str) -> None:
        """Nothing to hand back: a measurement keeps its last written value."""


class ServedLink:
    """One bench served to its PLC: the set-points published, the written measurements taken."""

    def __init__(self, bench: BenchMap, transport: "SharedServer", max_age_s: float = 2.0) -> None:
        self.bench = bench
        self.served = served_map(bench)
        self.board = Board(bench, self.served)
        self.port = PlantPort(self.board)
        self.device = Device(self.served.dmap, self.port)
        self.transport = transport
        self.max_age_s = max_age_s
        self.last_exchange_s = 0.0
        self.reasons: dict[str, str] = {}
        transport.add(self.device)

    @property
    def address(self) -> tuple[str, int | None]:
        return self.transport.host, self.transport.port

    def write(self, values: dict[str, float], t: float | None = None) -> None:
        """Publish the set-points (device units) the PLC will read next."""
        with self.port.lock:
            for i in self.bench.setpoints():
                p = self.served.dmap.point(i.name)
                self.board.values[p.signal] = codec.to_si(p, values[i.name])
            self.board.t = self.board.t + 1e-6 if t is None or t <= self.board.t else t

    def read(self) -> dict[str, float]:
        """The measurements (device units) as last written; NaN where none is fresh, with the
        reason in `reasons`."""
        now, out = time.monotonic(), {}
        self.reasons = {}
        with self.port.lock:
            for i in self.bench.measurements():
                p = self.served.dmap.point(i.name)
                written = self.board.written.get(p.command)
                if written is None:
                    self.reasons[i.name] = "silent: the bench PLC has not written it yet"
                elif now - written > self.max_age_s:
                    self.reasons[i.name] = f"silent: not written by the bench PLC for {now - written:.1f} s"
                out[i.name] = codec.to_device(p, self.board.values[p.command]) if i.name not in self.reasons else math.nan
        return out

    def exchange(self, values: dict[str, float], t: float | None = None) -> dict[str, float]:
        t0 = time.perf_counter()
        try:
            self.write(values, t)
            return self.read()
        finally:
            self.last_exchange_s = time.perf_counter() - t0

    def close(self) -> None:
        self.transport.release()


class SharedServer:
    """One Modbus TCP server (the gateway's transport) for the benches served on one address."""

    _lock = threading.Lock()
    _open: dict[tuple[str, int], "SharedServer"] = {}

    def __init__(self, host: str, port: int) -> None:
        self.host, self.requested = host, port
        self.devices: list[Device] = []
        self.transport: ModbusTcpTransport | None = None
        self.users = 0

    @classmethod
    def at(cls, host: str, port: int) -> "SharedServer":
        with cls._lock:
            key = (host, port)
            if key not in cls._open or port == 0:
                cls._open[key] = cls(host, port)
            return cls._open[key]

    @property
    def port(self) -> int | None:
        return self.transport.port if self.transport else None

    def add(self, device: Device) -> None:
        self.devices.append(device)
        self.users += 1

    def start(self) -> None:
        if self.transport is None:
            self.transport = ModbusTcpTransport(self.devices, host=self.host, port=self.requested,
                                                idle_timeout=0)
            self.transport.start()

    def release(self) -> None:
        """A bench is done with the server; the last one stops it and takes it off the address,
        also when it never started (a loop refused before its run): the next loop on that
        address must not find this one's devices."""
        self.users -= 1
        if self.users <= 0:
            if self.transport is not None:
                self.transport.stop()
                self.transport = None
            with self._lock:
                if self._open.get((self.host, self.requested)) is self:
                    del self._open[(self.host, self.requested)]
