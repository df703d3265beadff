"""Transport registry: protocol name → transport class, imported only when used."""
from __future__ import annotations

import importlib

from plant.errors import TransportError, closest

#: name -> "module:Class". A new transport adds one line here (plus module, contract test, README).
TRANSPORTS = {
    "modbus-tcp": "gateway.transports.modbus_tcp:ModbusTcpTransport",
    "modbus-rtu": "gateway.transports.modbus_rtu:ModbusRtuTransport",
    "canopen": "gateway.transports.canopen_node:CanopenTransport",
}


def transport_class(name: str) -> type:
    """The transport class registered as `name`."""
    if name not in TRANSPORTS:
        close = closest(name, TRANSPORTS, n=2)
        raise TransportError(f"transport {name!r}: not registered; known: {', '.join(TRANSPORTS)}"
                             + (f" (closest: {', '.join(close)})" if close else ""))
    module, cls = TRANSPORTS[name].split(":")
    return getattr(importlib.import_module(module), cls)
