"""CanopenLink: the twin as CANopen master of one bench node, the third exchange way of PHIL
(the first two: phil/master.py polls the bench PLC over Modbus TCP, phil/served.py serves it).

It has BenchLink's face (write, read, exchange, close, last_exchange_s, ExchangeError kinds) and
uses canopen's RemoteNode with the object dictionary built from the bench map
(phil/pdo_layout.py canopen_map, gateway/transports/canopen_od.py).

Configuration, once and again after the bench boots: the bench's PDO configuration is read by
SDO and checked against the layout derived from the same map (a mismatch names the PDO and the
fix); the mapping is never written. A real bench PLC often has a fixed mapping and the map is
the contract both sides derive from, so reading and checking works on fixed and remappable
nodes alike and finds a bench running another map. What the master does write is how often it
wants the measurements: transmission type 1 (every SYNC) on the bench's TPDOs; then NMT start.

Each exchange: the set-points go out in the bench's RPDOs (clamped to the map's range first:
a PDO has no answer, so a value the bench would refuse must never leave), then one SYNC; the
bench samples all its TPDOs at that SYNC and sends them. Synchronous rather than event-driven
because the loop's step is the sampling instant: the measurements answer this step's set-points,
all sampled together (a heat meter and the clock it is read with may sit in different PDOs), one
frame per PDO per step whatever the speed, and a bench's own event timer would either lag the
step or flood the bus at 200x. The link waits up to `timeout` for the answers; each TPDO's values
carry the wall time they arrived, and one older than `max_age_s` comes back NaN with the reason
("silent: ..."), which the guard (phil/safety.py) holds, flags, calls stale and stops on exactly
as for a Modbus bench (as ServedLink's silent PLC).
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

import can
import canopen
from canopen.sdo import SdoAbortedError, SdoCommunicationError

from gateway.maps import codec
from gateway.transports.can_bus import open_bus, parse_bus_spec
from gateway.transports.canopen_od import build_object_dictionary, pdo_bits
from phil.benchmap import BenchMap
from phil.master import ExchangeError
from phil.pdo_layout import Pdo, canopen_map, pdo_layout

SYNC_EVERY = 1                  # TPDO transmission type: sampled and sent at every SYNC
OPERATIONAL = 5


@dataclass
class Received:
    """The last frame of one TPDO (copied on the bus thread) and when it came."""

    count: int = 0
    data: bytes = b""
    wall: float | None = None


class CanopenLink:
    """A canopen RemoteNode of one bench on a python-can bus ("virtual:lab", "socketcand:...")."""

    def __init__(self, bench: BenchMap, bus: str, timeout: float = 0.5, max_age_s: float = 2.0) -> None:
        self.bench, self.timeout, self.max_age_s = bench, timeout, max_age_s
        self.co = canopen_map(bench)
        self.layout = pdo_layout(bench)
        self.spec = parse_bus_spec(bus)
        self.node_id = self.co.dmap.canopen.node_id
        self.network = canopen.Network(open_bus(self.spec))
        self.network.NOTIFIER_CYCLE = 0.1     # bounds how long close() waits for the bus thread
        self.network.connect()
        self.node = canopen.RemoteNode(self.node_id, build_object_dictionary(self.co.dmap))
        self.node.sdo.RESPONSE_TIMEOUT = timeout
        self.network.add_node(self.node)
        self.network.subscribe(0x700 + self.node_id, self._on_state)
        self.received = {p.number: Received() for p in self.layout if p.kind == "T"}
        self.by_cob_id = {p.cob_id(self.node_id): p.number for p in self.layout if p.kind == "T"}
        self.cond = threading.Condition()
        self.configured = self.started = False
        self.last_exchange_s = 0.0
        self.reasons: dict[str, str] = {}

    @property
    def where(self) -> str:
        return f"node 0x{self.node_id:02X} on {self.spec}"

    def close(self) -> None:
        self.network.disconnect()

    # ----------------------------------------------------------------------- configuration
    def _on_state(self, can_id: int, data: bytes, timestamp: float) -> None:
        """Boot-up (0) or heartbeat: a bench that rebooted is configured again, one that left
        OPERATIONAL is started again (bus thread: flags only, no SDO here)."""
        if data and data[0] == 0:
            self.configured = self.started = False
        elif data and data[0] & 0x7F != OPERATIONAL:
            self.started = False

    def _configure(self) -> None:
        try:
            self.node.tpdo.read()            # the bench's own configuration, by SDO
            self.node.rpdo.read()
            problems = self._mismatches()
            if problems:
                raise ExchangeError(self.bench.id, "exception", (
                    f"{self.where}: PDOs or map version differ from {self.bench.dmap.path} ({'; '.join(problems)}); "
                    f"run the bench with this map (twin bench {self.bench.id} --canopen {self.spec}) "
                    f"or give the bench PLC the EDS of `twin phil eds {self.bench.id}`"))
            for pdo in self.layout:
                if pdo.kind == "T":
                    pdo_map = self.node.tpdo[pdo.number]
                    if pdo_map.trans_type != SYNC_EVERY:
                        pdo_map.com_record[2].raw = SYNC_EVERY
                        pdo_map.trans_type = SYNC_EVERY
                    if self._on_tpdo not in pdo_map.callbacks:
                        pdo_map.add_callback(self._on_tpdo)
        except SdoCommunicationError as exc:
            raise ExchangeError(self.bench.id, "timeout", (
                f"{self.where}: no SDO answer ({exc}); is the bench node running "
                f"(twin bench {self.bench.id} --canopen {self.spec})?")) from None
        except SdoAbortedError as exc:
            raise ExchangeError(self.bench.id, "exception",
                                f"{self.where}: SDO abort 0x{exc.code:08X} reading its PDO configuration") from None
        except (can.CanError, OSError) as exc:
            raise ExchangeError(self.bench.id, "connection", f"{self.where}: cannot send SDO ({exc})") from None
        self.configured = True

    def _mismatches(self) -> list[str]:
        """How the bench's PDOs and map version differ from this map's (empty: they agree).
        Entries are compared as objects and sizes (what the bench has), named as this map
        names them."""
        out = []
        version = str(self.node.sdo[0x1009].raw)      # the map version the bench's EDS was built from
        if version != self.co.dmap.map_version:
            out.append(f"the bench serves map version {version}, the twin's is {self.co.dmap.map_version}")
        dmap = self.co.dmap
        for pdo in self.layout:
            pdo_map = (self.node.rpdo if pdo.kind == "R" else self.node.tpdo)[pdo.number]
            have = [(var.index, var.subindex, var.length) for var in pdo_map.map]
            want = [(p.co_index, p.co_sub, pdo_bits(p)) for p in map(dmap.point, pdo.points)]
            if not pdo_map.enabled or pdo_map.cob_id != pdo.cob_id(self.node_id):
                out.append(f"{pdo.name} {'disabled' if not pdo_map.enabled else f'at 0x{pdo_map.cob_id:X}'}, "
                           f"the map's at 0x{pdo.cob_id(self.node_id):X}")
            elif have != want:
                names = [var.name.rpartition(".")[2] if var.length == len(var.od) else
                         f"0x{var.index:04X}.{var.subindex} ({var.length} bits)" for var in pdo_map.map]
                out.append(f"{pdo.name} maps {', '.join(names) or 'nothing'}; the map: {', '.join(pdo.points)}")
        return out

    def _ready(self) -> None:
        if not self.configured:
            self._configure()
        if not self.started:
            self._send(lambda: setattr(self.node.nmt, "state", "OPERATIONAL"), "NMT start")
            self.started = True

    def _send(self, fn, what: str) -> None:
        try:
            fn()
        except (can.CanError, OSError) as exc:
            raise ExchangeError(self.bench.id, "connection", f"{self.where}: cannot send {what} ({exc})") from None

    # --------------------------------------------------------------------------- exchange
    def _on_tpdo(self, pdo_map) -> None:
        """canopen's callback on the bus thread: copy the frame, wake the exchange."""
        with self.cond:
            rx = self.received[self.by_cob_id[pdo_map.cob_id]]
            rx.count, rx.data, rx.wall = rx.count + 1, bytes(pdo_map.data), time.monotonic()
            self.cond.notify_all()

    def write(self, values: dict[str, float]) -> None:
        """Send the set-points (device units) in the bench's RPDOs; only the map's writable
        `to_bench` points are mapped there, so nothing else is ever sent."""
        self._ready()
        dmap = self.co.dmap
        for pdo in self.layout:
            if pdo.kind != "R":
                continue
            pdo_map = self.node.rpdo[pdo.number]
            for var, name in zip(pdo_map.map, pdo.points):
                p, want = dmap.point(name), values.get(name, math.nan)
                if math.isnan(want):
                    want = self.bench.interface(name).safe
                lo, hi = p.range
                var.raw = codec.to_raw(p, min(max(want, lo), hi))
            self._send(pdo_map.transmit, pdo.name)

    def read(self) -> dict[str, float]:
        """SYNC, then the measurements (device units) its TPDOs answered; NaN where a TPDO is
        older than max_age_s, with the reason in `reasons`."""
        self._ready()
        with self.cond:
            before = {n: rx.count for n, rx in self.received.items()}
        self._send(self.network.sync.transmit, "SYNC")
        with self.cond:
            self.cond.wait_for(lambda: all(rx.count > before[n] for n, rx in self.received.items()),
                               self.timeout)
            frames = {n: (rx.data, rx.wall) for n, rx in self.received.items()}
        now, out, self.reasons = time.monotonic(), {}, {}
        for pdo in self.layout:
            if pdo.kind == "T":
                out.update(self._values(pdo, *frames[pdo.number], now))
        return out

    def _values(self, pdo: Pdo, data: bytes, wall: float | None, now: float) -> dict[str, float]:
        pdo_map = self.node.tpdo[pdo.number]
        reason = ""
        if wall is None:
            reason = f"silent: no {pdo.name} from the bench yet ({self.where})"
        elif now - wall > self.max_age_s:
            reason = f"silent: no {pdo.name} from the bench for {now - wall:.1f} s ({self.where})"
        out = {}
        for var, name in zip(pdo_map.map, pdo.points):
            if reason:
                self.reasons[name], out[name] = reason, math.nan
                continue
            chunk = data[var.offset // 8:(var.offset + var.length) // 8]
            out[name] = float(codec.from_raw(self.co.dmap.point(name), var.od.decode_raw(chunk)))
        return out

    def exchange(self, values: dict[str, float]) -> dict[str, float]:
        """Set-points out, SYNC, measurements in; `last_exchange_s` is the wall time it took."""
        t0 = time.perf_counter()
        try:
            self.write(values)
            return self.read()
        finally:
            self.last_exchange_s = time.perf_counter() - t0
