"""ModbusRtuTransport: all devices of a house as slaves on one serial line (Modbus RTU)."""
from __future__ import annotations

from collections.abc import Iterable

from gateway.device.device import Device
from gateway.transports.base import Transport
from gateway.transports.modbus_server import ModbusServer


class ModbusRtuTransport(Transport):
    """Modbus RTU on a serial port (a real adapter, or one end of a pty pair in tests).

    Unknown unit ids get no reply (another slave's address on a shared line). Link faults per
    device: silent, late, drop (frame discarded, same as silent on a serial line), bad_crc (the
    last CRC byte of every answer is flipped, so the master's CRC check fails). Broadcast (unit 0)
    is not supported: such frames get no reply and change nothing.
    """

    name = "modbus-rtu"

    def __init__(self, devices: Iterable[Device], port: str, baudrate: int = 19200,
                 parity: str = "E", stopbits: int = 1) -> None:
        self.port = port
        self._server = ModbusServer(devices, "rtu", port, name=self.name,
                                    serial={"baudrate": baudrate, "parity": parity,
                                            "stopbits": stopbits})

    def start(self) -> None:
        self._server.start()

    def stop(self) -> None:
        self._server.stop()
