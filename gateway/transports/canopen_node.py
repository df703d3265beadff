"""The one canopen adapter: Devices as CiA 301 nodes on a bus (object dictionary: `canopen_od`).

`CanopenTransport(devices, bus)` serves each Device as a node on one bus. canopen 2.4's LocalNode
does only the SDO protocol and NMT parsing, so this module adds what a real node does (stack notes):
NMT states enforced (PDOs only in OPERATIONAL, no SDO in STOPPED, boot-up after reset), heartbeat
from 0x1017, TPDOs on their event timer or every n-th SYNC, RPDOs applied through the Device (its
validation and watchdog), the RPDO deadline (event timer, EMCY 0x8250), PDO remapping by SDO
(a PDO's configuration and the remapping check: `canopen_pdo`), SDO aborts from the Refusal table,
and CAN faults: error frames, error-passive and bus-off (silent until "recover"), each reported
through `on_event(dict)`.
"""
from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterable

import can
import canopen
from canopen.nmt import NmtBase
from canopen.sdo import SdoAbortedError

from gateway.maps.model import Point
from gateway.transports.base import Transport
from gateway.transports.can_bus import FAULT_KINDS, error_message, fault_kind, open_bus, parse_bus_spec
from gateway.transports.canopen_od import N_PDO, build_object_dictionary, point_objects
from gateway.transports.canopen_pdo import Pdo, mapping_abort
from plant.errors import TransportError

log = logging.getLogger(__name__)
PRE_OPERATIONAL, OPERATIONAL, STOPPED = 127, 5, 4
EMCY_PASSIVE, EMCY_BUS_OFF_RECOVERED, EMCY_PDO_LENGTH, EMCY_RPDO_TIMEOUT = 0x8120, 0x8140, 0x8210, 0x8250
#: SDO client command specifiers answered with abort 0x05040001 before canopen sees them: block
#: upload (5; canopen would answer as a plain upload), block download (6; canopen logs each), 7.
SDO_UNSERVED, SDO_ABORT_COMMAND = (5, 6, 7), 0x05040001


# ---------------------------------------------------------------------------------- one node
class DeviceNode(canopen.LocalNode):
    """A Device served as a CANopen node: live SDO values, NMT, heartbeat, PDOs, bus faults."""

    def __init__(self, device, transport: CanopenTransport) -> None:
        super().__init__(device.map.canopen.node_id, build_object_dictionary(device.map))
        self.device, self.transport = device, transport
        self.points = point_objects(device.map)
        self.lock = threading.RLock()
        self._write_callbacks.clear()   # NmtSlave would run its own heartbeat task; we produce it
        self.bus_off = self.error_passive = False
        self.history: list[int] = []
        self.tpdos: list[Pdo] = []
        self.rpdos: dict[int, Pdo] = {}
        self.hb_due = 0.0

    # canopen's LocalNode subscribes the SDO server and NMT slave directly; route them through us
    # so STOPPED and bus-off can silence the node.
    def associate_network(self, network: canopen.Network) -> None:
        self.network = network
        self.sdo.network = self.nmt.network = self.emcy.network = self      # sends go via send_message
        network.subscribe(self.sdo.rx_cobid, self._on_sdo)
        network.subscribe(0, self._on_nmt)
        network.subscribe(0x80, self._on_sync)

    def remove_network(self) -> None:
        for cob, fn in ((self.sdo.rx_cobid, self._on_sdo), (0, self._on_nmt), (0x80, self._on_sync),
                        *((p.cob_id, self._on_rpdo) for p in self.rpdos.values())):
            self.network.unsubscribe(cob, fn)

    def send_message(self, can_id: int, data: bytes, remote: bool = False) -> None:
        if self.bus_off or self.device.link.mode in ("silent", "drop", "bad_crc"):
            return
        self.network.send_message(can_id, data, remote)

    @property
    def state(self) -> int:
        return self.nmt._state  # canopen keeps the NMT state code only in this attribute

    # -------------------------------------------------------------------- SDO object access
    def stored(self, index: int, sub: int):
        obj = self._find_object(index, sub)
        return obj.decode_raw(super().get_data(index, sub))

    def get_data(self, index: int, subindex: int, check_readable: bool = False) -> bytes:
        obj = self._find_object(index, subindex)
        if check_readable and not obj.readable:
            raise SdoAbortedError(0x06010001)
        point = self.points.get((index, subindex))
        if point is not None:
            raw = self.device.read_point(point.name)
            if not isinstance(raw, (int, float, str, bool)):
                raise SdoAbortedError(raw.sdo_abort)
            return obj.encode_raw(raw) or b"\0"   # an empty string would abort "no data"
        if index == 0x1001:
            return bytes([self.error_register])
        if index == 0x1003:
            return obj.encode_raw(len(self.history) if subindex == 0 else
                                  (self.history[subindex - 1] if subindex <= len(self.history) else 0))
        return super().get_data(index, subindex, check_readable)

    def set_data(self, index: int, subindex: int, data: bytes, check_writable: bool = False) -> None:
        obj = self._find_object(index, subindex)
        if check_writable and not obj.writable:
            raise SdoAbortedError(0x06010002)
        if obj.fixed_size and len(data) * 8 != len(obj):
            raise SdoAbortedError(0x06070010)
        value = obj.decode_raw(bytes(data))
        point = self.points.get((index, subindex))
        if point is not None:
            self.write_point(point, value, "sdo")
            return
        if index == 0x1003:
            if value != 0:
                raise SdoAbortedError(0x06090030)   # only 0 (clear the history) may be written
            self.history.clear()
            return
        if index in range(0x1600, 0x1604) or index in range(0x1A00, 0x1A04):
            abort = mapping_abort(index, subindex, value, self.stored, self._find_object)
            if abort is not None:
                raise SdoAbortedError(abort)
        super().set_data(index, subindex, data)
        if index == 0x1017:
            self.hb_due = 0.0   # a new producer time restarts the heartbeat timer now
        if 0x1400 <= index < 0x1C00:
            self.load_pdos()    # canopen does not re-read a remapped PDO itself
        self.transport.wake()

    def write_point(self, point: Point, raw, via: str) -> None:
        refusal = self.device.write_point(point.name, raw, client=f"canopen-{via}",
                                          transport="canopen")
        if refusal is not None:
            raise SdoAbortedError(refusal.sdo_abort)

    def load_pdos(self) -> None:
        with self.lock:
            for pdo in self.rpdos.values():
                self.network.unsubscribe(pdo.cob_id, self._on_rpdo)
            self.tpdos = [Pdo(self.stored, 0x1800 + n, 0x1A00 + n) for n in range(N_PDO)]
            rpdos = [Pdo(self.stored, 0x1400 + n, 0x1600 + n) for n in range(N_PDO)]
            self.rpdos = {p.cob_id: p for p in rpdos if p.enabled and p.entries}
            for cob_id in self.rpdos:
                self.network.subscribe(cob_id, self._on_rpdo)

    # ---------------------------------------------------------------- bus callbacks
    def _on_sdo(self, can_id: int, data: bytes, timestamp: float) -> None:
        if self.bus_off or self.state == STOPPED or self.device.link.mode in ("silent", "drop", "bad_crc"):
            return
        if self.device.link.mode == "late":
            time.sleep(min(self.device.link.delay_s, 1.0))   # holds the bus thread, like a slow node
        with self.lock:
            ccs = data[0] >> 5 if data else 7
            # a short frame, or a segment with no transfer begun (canopen: a traceback each), too
            if len(data) < 8 or ccs in SDO_UNSERVED or (ccs in (0, 3) and self.sdo._buffer is None):
                head = bytes(data[1:4]).ljust(3, b"\0")
                self.sdo.send_response(bytes([0x80]) + head + SDO_ABORT_COMMAND.to_bytes(4, "little"))
                return
            self.sdo.on_request(can_id, data, timestamp)

    def _on_nmt(self, can_id: int, data: bytes, timestamp: float) -> None:
        if self.bus_off or len(data) < 2 or data[1] not in (0, self.id):
            return
        with self.lock:
            old = self.state
            NmtBase.on_command(self.nmt, can_id, data, timestamp)
            if self.state == 0:
                self.boot(reset_application=data[0] == 0x81)
            elif self.state != old:
                self._entered(old)

    def boot(self, reset_application: bool = False) -> None:
        """Power-on or NMT reset: defaults back, boot-up message, PRE-OPERATIONAL."""
        with self.lock:
            for index in list(self.data_store):
                if reset_application or index < 0x2000:
                    del self.data_store[index]
            self.load_pdos()
            old, self.nmt._state = self.state, 0
            self.send_message(0x700 + self.id, b"\x00")
            self.nmt._state = PRE_OPERATIONAL
            self.hb_due = 0.0
            self._entered(old)

    def _entered(self, old: int) -> None:
        for pdo in self.tpdos:
            pdo.due, pdo.syncs = 0.0, 0
        for pdo in self.rpdos.values():
            pdo.last_rx = None
        self.transport.report(self, "nmt", state=self.nmt.state, previous=old)
        self.transport.wake()

    def _on_sync(self, can_id: int, data: bytes, timestamp: float) -> None:
        if self.bus_off or self.state != OPERATIONAL:
            return
        with self.lock:
            for pdo in self.tpdos:
                if pdo.enabled and 1 <= pdo.trans_type <= 240:
                    pdo.syncs += 1
                    if pdo.syncs >= pdo.trans_type:
                        pdo.syncs = 0
                        self._transmit(pdo)

    def _on_rpdo(self, can_id: int, data: bytes, timestamp: float) -> None:
        if self.bus_off or self.state != OPERATIONAL:
            return      # PDOs are not processed outside OPERATIONAL (CiA 301)
        with self.lock:
            pdo = self.rpdos.get(can_id)
            if pdo is None:
                return
            if len(data) < pdo.size:
                self.emergency(EMCY_PDO_LENGTH)
                return
            pdo.last_rx, offset = self.transport.now(), 0
            for index, sub, bits in pdo.entries:
                chunk, offset = bytes(data[offset:offset + bits // 8]), offset + bits // 8
                point = self.points.get((index, sub))
                if point is None:
                    continue
                try:
                    self.write_point(point, self._find_object(index, sub).decode_raw(chunk), "rpdo")
                except SdoAbortedError as exc:   # already recorded as a refused write by the Device
                    log.debug("RPDO 0x%X %s refused: 0x%08X", can_id, point.name, exc.code)

    # ----------------------------------------------------------------- periodic work
    def tick(self, t: float) -> float:
        """Heartbeat, TPDO event timers, RPDO deadlines; returns the time of the next due work."""
        with self.lock:
            next_due = t + 0.05
            hb_ms = self.stored(0x1017, 0)
            if hb_ms:
                if t >= self.hb_due:
                    self.send_message(0x700 + self.id, bytes([self.state]))
                    self.hb_due = max(self.hb_due + hb_ms / 1000.0, t)
                next_due = min(next_due, self.hb_due)
            if self.state != OPERATIONAL:
                return next_due
            for pdo in self.tpdos:
                if pdo.enabled and pdo.entries and pdo.trans_type >= 0xFE and pdo.event_s > 0:
                    if t >= pdo.due:
                        self._transmit(pdo)
                        pdo.due = max(pdo.due + pdo.event_s, t) if pdo.due else t + pdo.event_s
                    next_due = min(next_due, pdo.due)
            for pdo in self.rpdos.values():
                if pdo.event_s and pdo.last_rx is not None and t - pdo.last_rx > pdo.event_s:
                    pdo.last_rx = None      # report once per silence
                    self.emergency(EMCY_RPDO_TIMEOUT)
                    self.transport.report(self, "rpdo_timeout", cob_id=pdo.cob_id)
            return next_due

    def _transmit(self, pdo: Pdo) -> None:
        payload = b"".join(self.get_data(i, s)[:bits // 8] for i, s, bits in pdo.entries)
        self.send_message(pdo.cob_id, payload)

    # ----------------------------------------------------------------------- faults
    @property
    def error_register(self) -> int:
        fault = 1 if self.device.fault_code() else 0          # bit 0 generic error
        comm = 0x10 if self.bus_off or self.error_passive else 0   # bit 4 communication
        return fault | comm

    def emergency(self, code: int) -> None:
        self.history = ([code] + self.history)[:8]
        if self.state != STOPPED:
            self.emcy.send(code, self.error_register)
        self.transport.report(self, "emcy", code=code)

    def fault(self, kind: str) -> None:
        with self.lock:
            if kind == "error_passive":
                self.error_passive = True
                self.emergency(EMCY_PASSIVE)
            elif kind == "bus_off":
                self.bus_off = True
            elif kind == "recover":
                was_off, self.bus_off, self.error_passive = self.bus_off, False, False
                if was_off:
                    self.emergency(EMCY_BUS_OFF_RECOVERED)
            self.transport.report(self, kind)


# ------------------------------------------------------------------------------- transport
class _FaultListener(can.Listener):
    """Error frames arrive here; canopen's own listener drops them."""

    def __init__(self, transport: CanopenTransport) -> None:
        self.transport = transport

    def on_message_received(self, msg: can.Message) -> None:
        kind = fault_kind(msg)
        if kind == "error_frame":
            self.transport.report(None, "error_frame", origin="bus")
        elif kind is not None:       # the bus (e.g. the hub) says our controller changed state
            for node in self.transport.nodes.values():
                node.fault(kind)


class CanopenTransport(Transport):
    """Serves Devices as CANopen nodes on one bus spec ("virtual:house1", "socketcand:...").

    Each Device becomes a node with its map's [canopen] node_id. Events (NMT changes, EMCY, CAN
    faults, RPDO deadline misses) go to `on_event` and to each Device's event stream.
    """

    name = "canopen"

    @classmethod
    def hooks(cls, runtime) -> dict:
        return {"on_event": runtime.event, "now": lambda: runtime.port.t}

    def __init__(self, devices: Iterable, bus: str = "virtual:house1", *,
                 on_event: Callable[[dict], None] | None = None,
                 now: Callable[[], float] = time.monotonic) -> None:
        self.spec = parse_bus_spec(bus)
        self.on_event, self.now = on_event, now
        self.devices = list(devices)
        ids = [d.map.canopen.node_id for d in self.devices]
        if len(set(ids)) != len(ids):
            raise TransportError(f"canopen on {self.spec}: node ids {ids} repeat; give each map's "
                                 "[canopen] node_id a unique value 1…127")
        self.network: canopen.Network | None = None
        self.nodes: dict[int, DeviceNode] = {}
        self._wake, self._stop = threading.Event(), threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Open the bus, boot every node (boot-up message, PRE-OPERATIONAL) and start timers."""
        network = canopen.Network(open_bus(self.spec))
        network.NOTIFIER_CYCLE = 0.1     # bounds how long stop() waits for the bus thread
        network.listeners.append(_FaultListener(self))
        network.connect()
        self.network = network
        for device in self.devices:
            node = DeviceNode(device, self)
            network.add_node(node)
            self.nodes[node.id] = node
            node.boot()
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=f"canopen-{self.spec}", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(2.0)
            self._thread = None
        if self.network is not None:
            self.network.disconnect()
            self.network = None
        self.nodes.clear()

    def wake(self) -> None:
        self._wake.set()

    def _run(self) -> None:
        while not self._stop.is_set():
            t = self.now()
            due = t + 0.05
            for node in list(self.nodes.values()):
                try:
                    due = min(due, node.tick(t))
                except Exception:   # server-loop boundary: log, continue serving
                    log.exception("canopen node 0x%X tick failed", node.id)
            self._wake.wait(max(0.0, due - self.now()))
            self._wake.clear()

    def inject(self, kind: str, node_id: int | None = None) -> None:
        """CAN fault: "error_frame" on the bus, or a node's controller "error_passive"/"bus_off"/"recover"."""
        if kind not in FAULT_KINDS:
            raise TransportError(f"canopen inject {kind!r}: unknown fault; use one of {', '.join(FAULT_KINDS)}")
        if node_id is not None and node_id not in self.nodes:
            raise TransportError(f"canopen inject {kind}: no node 0x{node_id:X}; serving "
                                 f"{', '.join(f'0x{n:X}' for n in self.nodes) or 'none'}")
        if kind == "error_frame":
            # python-can's socketcand client cannot send error frames; there it is a local event only.
            if self.network is not None and self.spec.interface == "virtual":
                self.network.bus.send(error_message(kind))
            self.report(self.nodes.get(node_id), "error_frame", origin="inject")
            return
        for node in ([self.nodes[node_id]] if node_id is not None else list(self.nodes.values())):
            node.fault(kind)

    def report(self, node: DeviceNode | None, kind: str, **detail) -> None:
        event = {"source": "canopen", "kind": kind, "bus": str(self.spec),
                 "node": node.id if node else None, "device": node.device.id if node else None, **detail}
        if node is not None:
            node.device.report({**event, "kind": f"canopen_{kind}"})
        if self.on_event is not None:
            try:
                self.on_event(event)
            except Exception:
                log.exception("canopen on_event hook failed")
