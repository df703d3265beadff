"""ModbusTcpTransport: all devices of a house on one Modbus TCP server, one unit id each."""
from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from gateway.device.device import Device
from gateway.transports.base import Transport
from gateway.transports.modbus_server import ModbusServer


class ModbusTcpTransport(Transport):
    """Modbus TCP on host:port (default 127.0.0.1, so nothing is exposed by accident).

    port 0 picks a free port; read `.port` after start(). `allow` limits clients to these IPs
    (others are disconnected and the attempt is reported as an event). A unit id nothing serves
    gets exception 0x0B (gateway target device failed to respond). Requests may be pipelined:
    every frame of a segment is answered with its own transaction id, and a frame split across
    segments is answered once it is complete. Link faults per device: silent, late, drop
    (connection closed); bad_crc does not apply to TCP (no CRC) and is ignored.

    Limits: at most `max_connections` open at once (one more is closed at once), and a connection
    that sends nothing for `idle_timeout` s is closed (0 = never); both are counted. Malformed
    frames are counted per client and kind and logged a few a minute (`traffic`, a TrafficLog);
    `on_event` receives those counts for the controller audit.
    """

    name = "modbus-tcp"

    @classmethod
    def hooks(cls, runtime) -> dict:
        # malformed frames and refused connections go to the audit only: a flood must not fill events.csv
        return {"on_event": runtime.audit.event}

    def __init__(self, devices: Iterable[Device], host: str = "127.0.0.1", port: int = 5020,
                 allow: Iterable[str] | None = None, max_connections: int = 64,
                 idle_timeout: float = 60.0, on_event: Callable[[dict], Any] | None = None) -> None:
        self._server = ModbusServer(devices, "tcp", (host, port), name=self.name, allow=allow,
                                    max_connections=max_connections, idle_timeout=idle_timeout,
                                    on_event=on_event)
        self.host = host
        self.traffic = self._server.traffic

    @property
    def port(self) -> int | None:
        return self._server.port

    def start(self) -> None:
        self._server.start()

    def stop(self) -> None:
        self._server.stop()
