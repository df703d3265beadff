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

One SYNC per step per bus: a lab puts several benches on one CAN bus, and every node on it
answers every SYNC. The links of the benches on one bus therefore share one `CanopenBus` (one
canopen Network, one python-can connection), the bus's only SYNC producer as CiA 301 expects;
its `exchange` sends every bench's RPDOs, then one SYNC, then collects each bench's TPDOs. So
all benches sample at the same instant, each answers its own set-points of this step (not a SYNC
meant for another bench's), and each TPDO is sent once a step rather than once per bench. A link
made with a bus spec string owns a bus of its own and exchanges alone, as before.
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
from plant.errors import ConfigError

SYNC_EVERY = 1                  # TPDO transmission type: sampled and sent at every SYNC
OPERATIONAL = 5


@dataclass
class Received:
    """The last frame of one TPDO (copied on the bus thread) and when it came."""

    count: int = 0
    data: bytes = b""
    wall: float | None = None


class CanopenBus:
    """One python-can bus ("virtual:lab", "socketcand:...") as one canopen Network, shared by the
    links of the benches on it: their nodes, and the bus's one SYNC producer."""

    def __init__(self, bus: str) -> None:
        self.spec = parse_bus_spec(bus)
        self.network = canopen.Network(open_bus(self.spec))
        self.network.NOTIFIER_CYCLE = 0.1     # bounds how long close() waits for the bus thread
        self.network.connect()
        self.links: list[CanopenLink] = []

    def link(self, bench: BenchMap, timeout: float = 0.5, max_age_s: float = 2.0) -> CanopenLink:
        return CanopenLink(bench, self, timeout, max_age_s)

    def _join(self, link: CanopenLink) -> None:
        # two masters' views of one node id would each take the other's TPDOs for their own
        for other in self.links:
            if other.node_id == link.node_id:
                raise ConfigError(f"{link.where}: bench {link.bench.id} and bench {other.bench.id} have the "
                                  f"same node id; give one of them another [canopen] node_id")
        self.network.add_node(link.node)
        self.links.append(link)

    def release(self, link: CanopenLink) -> None:
        """A link closed: its node leaves the network; the last one disconnects it."""
        if link not in self.links:
            return
        self.links.remove(link)
        if self.links:
            self.network.unsubscribe(0x700 + link.node_id, link._on_state)
            del self.network[link.node_id]
        else:
            self.network.disconnect()

    def exchange(self, values: dict[CanopenLink, dict[str, float]]
                 ) -> dict[CanopenLink, dict[str, float] | ExchangeError]:
        """Each link's set-points out (RPDOs), then ONE SYNC for all, then each link's measurements
        (its TPDOs sampled at that SYNC). A link that fails (ExchangeError) fails alone: its error
        is its answer, the others are still exchanged. Each link's `last_exchange_s` runs from its
        set-points going out to its last TPDO of the step coming in (or its wait ending)."""
        out: dict[CanopenLink, dict[str, float] | ExchangeError] = {}
        began, counts = {}, {}
        for link, wanted in values.items():
            began[link] = time.monotonic()
            try:
                link.write(wanted)
                counts[link] = link._counts()
            except ExchangeError as exc:
                out[link], link.last_exchange_s = exc, time.monotonic() - began[link]
        if counts:
            synced = time.monotonic()
            try:
                self.network.sync.transmit()
            except (can.CanError, OSError) as exc:
                for link in counts:
                    out[link] = ExchangeError(link.bench.id, "connection", f"{link.where}: cannot send SYNC ({exc})")
                    link.last_exchange_s = time.monotonic() - began[link]
                counts = {}
            for link, before in counts.items():
                # one deadline from the one SYNC: a silent bench costs the step one timeout, not one each
                out[link] = link._collect(before, synced + link.timeout)
                link.last_exchange_s = link.answered - began[link]
        return {link: out[link] for link in values}


class CanopenLink:
    """A canopen RemoteNode of one bench on a python-can bus: a bus spec ("virtual:lab",
    "socketcand:...") opens a bus of this link's own, a CanopenBus shares that one."""

    def __init__(self, bench: BenchMap, bus: str | CanopenBus, timeout: float = 0.5, max_age_s: float = 2.0) -> None:
        self.bench, self.timeout, self.max_age_s = bench, timeout, max_age_s
        self.co = canopen_map(bench)
        self.layout = pdo_layout(bench)
        self.node_id = self.co.dmap.canopen.node_id
        self.bus = CanopenBus(bus) if isinstance(bus, str) else bus
        self.spec, self.network = self.bus.spec, self.bus.network
        self.node = canopen.RemoteNode(self.node_id, build_object_dictionary(self.co.dmap))
        self.node.sdo.RESPONSE_TIMEOUT = timeout
        self.bus._join(self)
        self.network.subscribe(0x700 + self.node_id, self._on_state)
        self.received = {p.number: Received() for p in self.layout if p.kind == "T"}
        self.by_cob_id = {p.cob_id(self.node_id): p.number for p in self.layout if p.kind == "T"}
        self.cond = threading.Condition()
        self.configured = self.started = False
        self.last_exchange_s = 0.0
        self.answered = 0.0               # monotonic time the last read's measurements were in
        self.reasons: dict[str, str] = {}

    @property
    def where(self) -> str:
        return f"node 0x{self.node_id:02X} on {self.spec}"

    def close(self) -> None:
        self.bus.release(self)

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
        older than max_age_s, with the reason in `reasons`. The SYNC goes to the whole bus: with
        other benches on it, exchange them together through CanopenBus.exchange."""
        self._ready()
        before = self._counts()
        synced = time.monotonic()
        self._send(self.network.sync.transmit, "SYNC")
        return self._collect(before, synced + self.timeout)

    def _counts(self) -> dict[int, int]:
        with self.cond:
            return {n: rx.count for n, rx in self.received.items()}

    def _collect(self, before: dict[int, int], deadline: float) -> dict[str, float]:
        """The measurements of the TPDOs received after `before`, waited for until `deadline`."""
        with self.cond:
            done = self.cond.wait_for(lambda: all(rx.count > before[n] for n, rx in self.received.items()),
                                      max(deadline - time.monotonic(), 0.0))
            frames = {n: (rx.data, rx.wall) for n, rx in self.received.items()}
        now, out, self.reasons = time.monotonic(), {}, {}
        self.answered = max(wall for _, wall in frames.values()) if done and frames else now
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
