"""ModbusRtuTransport: all devices of a house as slaves on one serial line (Modbus RTU)."""
from __future__ import annotations

from collections.abc import Iterable

from gateway.device.device import Device
from gateway.transports.base import Transport
from gateway.transports.modbus_server import ModbusServer
from gateway.transports.virtual_serial import VirtualSerialPair

#: the port name that makes the transport bring its own line (see VirtualSerialPair).
VIRTUAL = "virtual"


class ModbusRtuTransport(Transport):
    """Modbus RTU on a serial port (a real adapter, or one end of a pty pair in tests).

    Unknown unit ids get no reply (another slave's address on a shared line). Link faults per
    device: silent, late, drop (frame discarded, same as silent on a serial line), bad_crc (the
    last CRC byte of every answer is flipped, so the master's CRC check fails). Broadcast (unit 0)
    is not supported: such frames get no reply and change nothing.

    With `port="virtual"` the transport brings its own line, a VirtualSerialPair: it serves on one
    end, and `client_path` (set on start) names the other end for the master to open (parity N).
    """

    name = "modbus-rtu"

    def __init__(self, devices: Iterable[Device], port: str, baudrate: int = 19200,
                 parity: str = "E", stopbits: int = 1) -> None:
        self.port = port
        if port == VIRTUAL:
            # a pty has no line coding, and some kernels refuse PARENB on one (tcsetattr EINVAL)
            parity = "N"
        self.client_path: str | None = None
        self._virtual = VirtualSerialPair() if port == VIRTUAL else None
        self._server = ModbusServer(devices, "rtu", port, name=self.name,
                                    serial={"baudrate": baudrate, "parity": parity,
                                            "stopbits": stopbits})

    def start(self) -> None:
        if self._virtual is not None:
            self._virtual.start()
            self._server.address = self._virtual.server_path
            self.client_path = self._virtual.client_path
        try:
            self._server.start()
        except BaseException:
            if self._virtual is not None:
                self._virtual.close()
            raise

    def stop(self) -> None:
        self._server.stop()
        if self._virtual is not None:
            self._virtual.close()
