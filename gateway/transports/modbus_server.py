"""The pymodbus 3.16 adapter (with its request handler, modbus_requests.py, the only modules that
import pymodbus on the server side).

One pymodbus server (TCP or RTU) serves several Devices, one unit id each. pymodbus's simulator
API is used as the stack notes describe: one SimDevice per unit whose async `action` callback
fills registers from the Device on reads and passes writes to the Device, returning an ExcCodes
member for a Refusal. Subclassing datablocks is ignored by pymodbus 3.16, so live values must
come through `action`.

The three requests a PLC sends every scan (FC3/FC4 register reads, FC6 single write) are
answered in the request handler straight from the Device (`_direct`): the same Device calls, but
without the simulator's per-register checks and the action coroutine, which cost a fifth of a
loopback round trip. Everything else goes through the simulator and `action`.

Per request, the connection's handler (gateway/transports/modbus_requests.py) adds what pymodbus
cannot do through `action`: client context and whitelist, link faults, identification, unknown
unit ids, pipelined frames, connection limits and malformed frames.
The server loop runs in its own thread (gateway/event_loop.py ServerThread); Device calls are
thread-safe. What a Device answers, without pymodbus's types: gateway/transports/modbus_answers.py.
"""
from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from typing import Any

from pymodbus.constants import ExcCodes
from pymodbus.framer import FramerType
from pymodbus.server import ModbusSerialServer, ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

from gateway.device.device import FC_TABLE, Device
from gateway.event_loop import ServerThread
from gateway.maps.model import BIT_TABLES, TABLES
from gateway.transports.modbus_answers import read_into, table_span
from gateway.transports.modbus_requests import REQUEST, RequestHandler
from gateway.transports.traffic_log import TrafficLog, quiet_pymodbus
from plant.errors import TransportError

log = logging.getLogger(__name__)


def _simdata(device: Device, table: str) -> list[SimData]:
    """One block spanning the table's mapped addresses; the action decides what is mapped."""
    span = table_span(device, table)
    lo, count = span if span is not None else (0, 1)
    if table in BIT_TABLES:
        return [SimData(lo, count=count, values=False, datatype=DataType.BITS)]
    return [SimData(lo, count=count, datatype=DataType.REGISTERS)]


def _action(device: Device, transport: str):
    async def action(fc: int, start: int, address: int, count: int, registers: list[int],
                     values: list[int] | list[bool] | None) -> ExcCodes | None:
        try:
            _, pdu, client = REQUEST.get((device, None, ""))
            table = FC_TABLE.get(fc)
            if table is None:
                return ExcCodes.ILLEGAL_FUNCTION
            if values is not None:
                refusal = device.write_registers(table, address, [int(v) for v in values],
                                                 client, transport)
            else:
                # pymodbus passes the number of 16-bit words; the request holds the bit count.
                bits = getattr(pdu, "count", 0) if pdu is not None and fc in (1, 2) else 1
                refusal = read_into(device, table, start, address, count, registers, bits)
            return ExcCodes(refusal.modbus_code) if refusal else None
        except Exception:  # server-loop boundary: log, answer 04, keep serving
            log.exception("%s: action failed", device.id)
            return ExcCodes.DEVICE_FAILURE
    return action


class ModbusServer:
    """A pymodbus server for several devices, run in its own thread.

    kind "tcp": `address` = (host, port), port 0 = ephemeral (see `.port` after start).
    kind "rtu": `address` = serial port path; `serial` = dict(baudrate, parity, stopbits, bytesize).
    `allow` = client IPs allowed on TCP (None = anyone). TCP limits: `max_connections` open at
    once, `idle_timeout` s without a received byte (0 = none). `on_event(dict)` receives the
    malformed-frame counts and connection refusals/closures (the controller audit).
    """

    def __init__(self, devices: Iterable[Device], kind: str, address: Any, *, name: str,
                 allow: Iterable[str] | None = None, serial: dict | None = None,
                 max_connections: int = 64, idle_timeout: float = 60.0,
                 on_event: Callable[[dict], Any] | None = None) -> None:
        self.devices = {d.unit_id: d for d in devices}
        if len(self.devices) == 0:
            raise TransportError(f"{name}: no devices to serve; pass at least one Device")
        self.kind, self.address, self.name = kind, address, name
        self.allow = set(allow) if allow is not None else None
        self.serial = serial or {}
        if max_connections < 1 or idle_timeout < 0:
            raise TransportError(f"{name}: max_connections {max_connections}, idle_timeout {idle_timeout} s; "
                                 "need at least 1 connection and a timeout >= 0 s (0 = none)")
        self.max_connections, self.idle_timeout = max_connections, idle_timeout
        self.traffic = TrafficLog(name, log, on_event=on_event)
        self.port: int | None = None
        self._server: Any = None
        self._thread = ServerThread(f"{name}-server")

    def start(self) -> None:
        quiet_pymodbus()
        self._thread.start(self._open, f"{self.name} {self.address}",
                           "check the address/port is free and the serial device exists")

    def stop(self) -> None:
        if not self._thread.running:
            return
        if self._server is not None:
            try:
                self._thread.call(self._server.shutdown(), 5)
            except Exception:  # shutting down anyway; a half-closed socket must not block stop()
                log.exception("%s: shutdown", self.name)
        self._thread.stop()
        self.traffic.flush()

    async def _open(self) -> None:
        sims = [SimDevice(id=d.unit_id, simdata=tuple(_simdata(d, t) for t in TABLES_ORDER),
                          action=_action(d, self.name)) for d in self.devices.values()]
        if self.kind == "tcp":
            server = _TcpServer(sims, address=tuple(self.address), framer=FramerType.SOCKET)
        else:
            server = _SerialServer(sims, port=self.address, framer=FramerType.RTU,
                                   reconnect_delay=0.5, **self.serial)
        server.gw_devices, server.gw_allow, server.gw_name = self.devices, self.allow, self.name
        server.gw_port_name, server.gw_kind, server.gw_owner = self.address, self.kind, self
        server.gw_max_connections, server.gw_idle_s = self.max_connections, self.idle_timeout
        self._server = server
        await server.serve_forever(background=True)
        if self.kind == "tcp":
            self.port = server.transport.sockets[0].getsockname()[1]


#: pymodbus's non-shared block tuple order: coils, discrete inputs, holding, input registers.
TABLES_ORDER = ("coil", "discrete", "holding", "input")
assert set(TABLES_ORDER) == set(TABLES)


class _TcpServer(ModbusTcpServer):
    def callback_new_connection(self) -> RequestHandler:
        return RequestHandler(self, self.trace_packet, self.trace_pdu, self.trace_connect)


class _SerialServer(ModbusSerialServer):
    def callback_new_connection(self) -> RequestHandler:
        return RequestHandler(self, self.trace_packet, self.trace_pdu, self.trace_connect)
