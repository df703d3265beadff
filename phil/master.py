"""BenchLink: the twin as Modbus TCP master of one bench PLC (the only module that imports the
pymodbus client); PlcLink: the same client on the other side, a bench PLC polling the twin that
serves it (phil/served.py, the bench emulator's `--plc` mode).

Per exchange it writes the set-points (one FC16 per contiguous holding block) and reads the
measurements (one FC4/FC3 per contiguous block), converting with the map's codec
(gateway/maps/codec.py) to and from the map's device units. Only points the map declares
writable and `to_bench` are ever written. Every failure is an ExchangeError naming the bench and
what happened ("timeout", "exception 04", "refused"), never a pymodbus type.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass

from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ModbusException

from gateway.maps import codec
from gateway.maps.model import Point
from phil.benchmap import BenchMap
from plant.errors import TransportError

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)


class ExchangeError(TransportError):
    """One failed request to a bench: `kind` is timeout, exception, or connection."""

    def __init__(self, bench: str, kind: str, detail: str) -> None:
        super().__init__(f"bench {bench}: {kind}: {detail}")
        self.bench, self.kind, self.detail = bench, kind, detail


@dataclass(frozen=True)
class Block:
    """Contiguous registers of one table, read or written in one request."""

    table: str
    address: int
    points: tuple[Point, ...]

    @property
    def count(self) -> int:
        return sum(p.words for p in self.points)


def blocks(points: list[Point]) -> list[Block]:
    """Group points into contiguous runs per table (address order)."""
    out: list[Block] = []
    run: list[Point] = []
    for p in sorted(points, key=lambda q: (q.table, q.address)):
        if run and (p.table != run[-1].table or p.address != run[-1].address + run[-1].words):
            out.append(Block(run[0].table, run[0].address, tuple(run)))
            run = []
        run.append(p)
    if run:
        out.append(Block(run[0].table, run[0].address, tuple(run)))
    return out


class BenchLink:
    """A pymodbus TCP client to one bench, with the map's set-point and measurement blocks."""

    def __init__(self, bench: BenchMap, host: str, port: int, timeout: float = 0.5,
                 retries: int = 1) -> None:
        self.bench, self.host, self.port = bench, host, port
        dmap = bench.dmap
        writable = [dmap.point(i.name) for i in bench.setpoints() if dmap.point(i.name).writable]
        self.write_blocks = blocks(writable)
        self.read_blocks = blocks([dmap.point(i.name) for i in bench.measurements()])
        self.client = ModbusTcpClient(host, port=port, timeout=timeout, retries=retries,
                                      reconnect_delay=0.05, reconnect_delay_max=0.5)
        self.unit = dmap.unit_id
        self.last_exchange_s = 0.0

    def close(self) -> None:
        self.client.close()

    def _check(self, result: object, what: str) -> object:
        if result is None:
            self.client.close()
            raise ExchangeError(self.bench.id, "timeout", f"no answer to {what}")
        if result.isError():
            code = getattr(result, "exception_code", None)
            if code is None:
                # a late answer may still arrive on this connection and be taken for the next
                # request's: start the next exchange on a fresh connection
                self.client.close()
                raise ExchangeError(self.bench.id, "timeout", f"{what}: {result}")
            raise ExchangeError(self.bench.id, "exception", f"exception {int(code):02d} to {what}")
        return result

    def _call(self, fn, *args, what: str, **kw) -> object:
        try:
            if not self.client.connected and not self.client.connect():
                raise ExchangeError(self.bench.id, "connection", f"cannot connect to {self.host}:{self.port}")
            return self._check(fn(*args, device_id=self.unit, **kw), what)
        except ModbusException as exc:
            self.client.close()
            raise ExchangeError(self.bench.id, "timeout", f"{what}: {exc}") from None
        except OSError as exc:
            self.client.close()
            raise ExchangeError(self.bench.id, "connection", f"{what}: {exc}") from None

    def write(self, values: dict[str, float]) -> None:
        """Write the set-points (device units) the map declares writable; others are ignored."""
        for block in self.write_blocks:
            words: list[int] = []
            for p in block.points:
                words += codec.to_registers(p, codec.to_raw(p, values[p.name]))
            self._call(self.client.write_registers, block.address, words,
                       what=f"write {block.table} {block.address}+{block.count}")

    def read(self) -> dict[str, float]:
        """The measurements in device units (NaN stays NaN, the guard judges it)."""
        out: dict[str, float] = {}
        for block in self.read_blocks:
            fn = self.client.read_input_registers if block.table == "input" else self.client.read_holding_registers
            result = self._call(fn, block.address, count=block.count,
                                what=f"read {block.table} {block.address}+{block.count}")
            regs, i = list(result.registers), 0
            for p in block.points:
                out[p.name] = float(codec.from_raw(p, codec.from_registers(p, regs[i:i + p.words])))
                i += p.words
        return out

    def exchange(self, values: dict[str, float]) -> dict[str, float]:
        """Set-points out, measurements in; `last_exchange_s` is the wall time it took."""
        t0 = time.perf_counter()
        try:
            self.write(values)
            return self.read()
        finally:
            self.last_exchange_s = time.perf_counter() - t0


class PlcLink(BenchLink):
    """A bench PLC's client of the twin that serves it: `read()` gives the set-points, `write()`
    sends the measurements (device units), on the served map's registers (phil/served.py)."""

    def __init__(self, served: BenchMap, host: str, port: int, timeout: float = 0.5,
                 retries: int = 1) -> None:
        super().__init__(served, host, port, timeout, retries)
        dmap = served.dmap
        self.read_blocks = blocks([dmap.point(i.name) for i in served.setpoints()])
        self.write_blocks = blocks([dmap.point(i.name) for i in served.measurements()])
