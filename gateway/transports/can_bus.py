"""The one python-can adapter: opens a CAN bus from a spec string and names the CAN fault kinds.

Bus specs (one string, so the CLI, run configs and tests say the same thing):

    virtual:<channel>                      python-can's in-process bus; one process only
    socketcand:<host>:<port>[:<channel>]   a socketcand server, e.g. `twin can-hub` (channel can0)
    socketcan:<interface>                  Linux SocketCAN (needs a kernel with AF_CAN)

Every bus is opened with `ignore_config=True` and explicit options, so a `~/.canrc` or
`CAN_INTERFACE` variable cannot change a run.

Faults use the FMI-LS-BUS CAN vocabulary: an error frame on the wire, a controller going
error-passive or bus-off, and recovery from bus-off. On the wire they travel as SocketCAN-style error
frames whose identifier carries the Linux `can/error.h` class bits, because that is the only error
information python-can's socketcand client keeps (it drops the error frame's data bytes).
"""
from __future__ import annotations

import socket
from dataclasses import dataclass

import can

from plant.errors import TransportError

# Linux can/error.h error classes, carried in the identifier of an error frame.
CAN_ERR_CRTL = 0x004        # controller problem (here: went error-passive)
CAN_ERR_PROT = 0x008        # protocol violation (here: an injected error frame)
CAN_ERR_BUSOFF = 0x040
CAN_ERR_BUSERROR = 0x080
CAN_ERR_RESTARTED = 0x100   # controller restarted after bus-off
CAN_ERR_CRTL_RX_PASSIVE = 0x10
CAN_ERR_CRTL_TX_PASSIVE = 0x20

FAULT_KINDS = ("error_frame", "error_passive", "bus_off", "recover")
_CLASS_OF_KIND = {
    "error_frame": CAN_ERR_PROT | CAN_ERR_BUSERROR,
    "error_passive": CAN_ERR_CRTL,
    "bus_off": CAN_ERR_BUSOFF,
    "recover": CAN_ERR_RESTARTED,
}
# Checked in this order: a frame may carry several classes, the most severe wins.
_KIND_ORDER = (("bus_off", CAN_ERR_BUSOFF), ("recover", CAN_ERR_RESTARTED),
               ("error_passive", CAN_ERR_CRTL), ("error_frame", CAN_ERR_PROT | CAN_ERR_BUSERROR))

SPEC_FORMS = "virtual:<channel>, socketcand:<host>:<port>[:<channel>] or socketcan:<interface>"
DEFAULT_SOCKETCAND_PORT = 29536


@dataclass(frozen=True)
class BusSpec:
    """A parsed bus spec: python-can interface name, channel, and the TCP address for socketcand."""

    interface: str
    channel: str
    host: str = ""
    port: int = 0

    def __str__(self) -> str:
        if self.interface == "socketcand":
            return f"socketcand:{self.host}:{self.port}:{self.channel}"
        return f"{self.interface}:{self.channel}"


def parse_bus_spec(spec: str) -> BusSpec:
    """Parse 'virtual:house1', 'socketcand:127.0.0.1:29536:can0' or 'socketcan:can0'."""
    kind, _, rest = spec.partition(":")
    where = f"CAN bus spec {spec!r}"
    if kind == "virtual" and rest:
        return BusSpec("virtual", rest)
    if kind == "socketcan" and rest:
        return BusSpec("socketcan", rest)
    if kind == "socketcand":
        parts = rest.split(":")
        if len(parts) in (2, 3) and parts[0] and parts[1].isdigit():
            channel = parts[2] if len(parts) == 3 and parts[2] else "can0"
            port = int(parts[1])
            if 0 < port < 65536:
                return BusSpec("socketcand", channel, parts[0], port)
        raise TransportError(f"{where}: host and port are required; "
                             f"write socketcand:<host>:<port>[:<channel>], "
                             f"e.g. socketcand:127.0.0.1:{DEFAULT_SOCKETCAND_PORT}:can0")
    raise TransportError(f"{where}: unknown form; use {SPEC_FORMS}")


def open_bus(spec: str | BusSpec, connect_timeout_s: float = 2.0) -> can.BusABC:
    """Open a python-can bus for `spec`; raises TransportError with the fix when it cannot."""
    parsed = spec if isinstance(spec, BusSpec) else parse_bus_spec(spec)
    where = f"CAN bus {parsed}"
    if parsed.interface == "socketcand":
        # python-can retries a refused connect in a busy loop for 10 s; probe first to fail fast.
        try:
            socket.create_connection((parsed.host, parsed.port), connect_timeout_s).close()
        except OSError as exc:
            raise TransportError(f"{where}: cannot connect ({exc}); start a hub with "
                                 f"`twin can-hub --host {parsed.host} --port {parsed.port}`") from exc
        options = {"host": parsed.host, "port": parsed.port,
                   # Without TCP_NODELAY/QUICKACK, Nagle + delayed ACK add 40 ms tails to SDO.
                   "tcp_tune": True}
    elif parsed.interface == "virtual":
        options = {"receive_own_messages": False}
    else:
        options = {}
    try:
        return can.Bus(interface=parsed.interface, channel=parsed.channel,
                       ignore_config=True, **options)
    except (can.CanError, OSError, ValueError, ImportError) as exc:
        fix = ("this kernel may lack SocketCAN; use virtual:<channel> in one process or "
               "socketcand via `twin can-hub`" if parsed.interface == "socketcan"
               else "check the spec and that the server is running")
        raise TransportError(f"{where}: cannot open ({exc}); {fix}") from exc


def error_message(kind: str, timestamp: float = 0.0) -> can.Message:
    """The error frame that announces fault `kind` (one of FAULT_KINDS)."""
    if kind not in _CLASS_OF_KIND:
        raise TransportError(f"CAN fault {kind!r}: unknown kind; use one of {', '.join(FAULT_KINDS)}")
    data = bytearray(8)
    if kind == "error_passive":
        data[1] = CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE
    return can.Message(arbitration_id=error_class(kind), is_extended_id=True,
                       is_error_frame=True, data=data, timestamp=timestamp)


def error_class(kind: str) -> int:
    """Linux error-class bits used in the identifier of the error frame for `kind`."""
    return _CLASS_OF_KIND[kind]


def fault_kind(msg: can.Message) -> str | None:
    """The fault kind an error frame announces, or None for a data frame."""
    if not msg.is_error_frame:
        return None
    return kind_of_class(msg.arbitration_id)


def kind_of_class(error_id: int) -> str:
    """Map Linux error-class bits to a fault kind; unknown classes count as a plain error frame."""
    for kind, bits in _KIND_ORDER:
        if error_id & bits:
            return kind
    return "error_frame"
