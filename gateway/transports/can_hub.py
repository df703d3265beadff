"""A small CAN bus over TCP: an asyncio hub speaking enough of the socketcand protocol for python-can.

This kernel has no SocketCAN, and python-can's `virtual` bus works inside one process only, so
processes (the gateway, a firmware example, `candump`-like tools) meet on this hub instead. Each
client is python-can's `socketcand` interface (`can_bus.open_bus("socketcand:host:port:can0")`).

Protocol subset (socketcand rawmode, ASCII over TCP):

    hub -> client   < hi >                       on connect
    client -> hub   < open can0 >                hub answers < ok >
    client -> hub   < rawmode >                  hub answers < ok >; frames flow from now on
    client -> hub   < send 601 8 40 0 10 0 0 0 0 0 >      (id hex, length, bytes in hex)
    hub -> others   < frame 601 1700000000.123456 4000100000000000 >
    hub -> client   < error 00000040 1700000000.123456 0000000000000000 >   (an error frame)

Every frame goes to every other client that opened the same channel, as on a real bus (a sender
does not see its own frames). Faults (`inject`): "error_frame" goes to all clients; "error_passive",
"bus_off" and "recover" concern one client (or all): a bus-off client neither sends nor receives
until "recover". Each fault, connect and disconnect is reported through `on_event(dict)`.
"""
from __future__ import annotations

import asyncio
import logging
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from gateway.transports.can_bus import FAULT_KINDS, error_class
from plant.errors import TransportError

log = logging.getLogger(__name__)

# python-can's client reads the "< ok >" of rawmode with one recv() and compares it exactly, so a
# frame sent right behind the "< ok >" would break its handshake. Frames for a new client are held
# this long and then delivered in order.
JOIN_DELAY_S = 0.03
MAX_LINE = 256


@dataclass
class _Client:
    name: str
    writer: asyncio.StreamWriter
    channel: str = ""
    raw: bool = False
    held: list[bytes] | None = field(default_factory=list)   # None once the join delay is over
    bus_off: bool = False
    error_passive: bool = False

    def deliver(self, line: bytes) -> bool:
        if self.bus_off or not self.raw:
            return False
        if self.held is not None:
            self.held.append(line)
        else:
            self.writer.write(line)
        return True


class CanHub:
    """A socketcand-speaking TCP hub; `start()` serves it from a background thread."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0,
                 on_event: Callable[[dict], None] | None = None,
                 join_delay_s: float = JOIN_DELAY_S) -> None:
        self.host = host
        self._port = port
        self.on_event = on_event
        self.join_delay_s = join_delay_s
        self.frames_in = 0
        self.frames_out = 0
        self._clients: dict[str, _Client] = {}
        self._server: asyncio.base_events.Server | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._stopped: asyncio.Event | None = None

    # --- life cycle -------------------------------------------------------------------------
    @property
    def port(self) -> int:
        """The bound TCP port (the ephemeral one when constructed with port 0)."""
        return self._port

    @property
    def spec(self) -> str:
        """The bus spec a client passes to `can_bus.open_bus`."""
        return f"socketcand:{self.host}:{self._port}:can0"

    async def open(self) -> None:
        """Bind the listening socket (raises TransportError if the address is taken)."""
        self._loop = asyncio.get_running_loop()
        self._stopped = asyncio.Event()
        try:
            self._server = await asyncio.start_server(self._serve_client, self.host, self._port)
        except OSError as exc:
            raise TransportError(f"can-hub {self.host}:{self._port}: cannot listen ({exc}); "
                                 "choose another --port or stop the other hub") from exc
        self._port = self._server.sockets[0].getsockname()[1]

    async def serve_forever(self) -> None:
        """Open (if needed) and serve until `stop()`."""
        if self._server is None:
            await self.open()
        assert self._stopped is not None
        await self._stopped.wait()
        await self._close()

    def start(self) -> CanHub:
        """Serve from a daemon thread; returns once the port is bound."""
        ready = threading.Event()
        failure: list[BaseException] = []

        async def main() -> None:
            try:
                await self.open()
            except BaseException as exc:  # handed to the starting thread
                failure.append(exc)
                ready.set()
                return
            ready.set()
            await self.serve_forever()

        self._thread = threading.Thread(target=asyncio.run, args=(main(),),
                                        name=f"can-hub-{self.host}", daemon=True)
        self._thread.start()
        ready.wait(5.0)
        if failure:
            raise failure[0]
        return self

    def stop(self) -> None:
        """Close every client and the listening socket; joins the thread started by `start()`."""
        if self._loop is not None and self._stopped is not None and not self._loop.is_closed():
            try:
                self._loop.call_soon_threadsafe(self._stopped.set)
            except RuntimeError:  # loop already finished
                pass
        if self._thread is not None:
            self._thread.join(5.0)
            self._thread = None

    async def _close(self) -> None:
        assert self._server is not None
        self._server.close()
        for client in list(self._clients.values()):
            client.writer.close()
        await self._server.wait_closed()

    # --- faults -----------------------------------------------------------------------------
    def peers(self) -> list[str]:
        """Names ("host:port") of the connected clients, in connection order."""
        return list(self._clients)

    def wait_for_peers(self, count: int, timeout_s: float = 5.0) -> bool:
        """Wait until `count` clients are in rawmode and past their join delay."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if sum(1 for c in list(self._clients.values()) if c.raw and c.held is None) >= count:
                return True
            time.sleep(0.005)
        return False

    def inject(self, kind: str, peer: str | None = None) -> None:
        """Inject fault `kind` (error_frame, error_passive, bus_off, recover) for `peer` or all."""
        if kind not in FAULT_KINDS:
            raise TransportError(f"can-hub inject {kind!r}: unknown fault; use one of "
                                 f"{', '.join(FAULT_KINDS)}")
        if peer is not None and peer not in self._clients:
            raise TransportError(f"can-hub inject {kind}: no client {peer!r}; connected: "
                                 f"{', '.join(self._clients) or 'none'}")
        if self._loop is None:
            raise TransportError("can-hub inject: the hub is not running; call start() first")
        self._loop.call_soon_threadsafe(self._inject, kind, peer)

    def _inject(self, kind: str, peer: str | None) -> None:
        targets = [c for c in self._clients.values() if peer is None or c.name == peer]
        line = _error_line(error_class(kind))
        if kind == "error_frame":
            # An error frame destroys the frame on the wire; every node sees it.
            for client in self._clients.values():
                client.deliver(line)
        for client in targets:
            if kind == "bus_off":
                client.deliver(line)     # the controller reports, then goes silent
                client.bus_off = True
            elif kind == "recover":
                client.bus_off = client.error_passive = False
                client.deliver(line)
            elif kind == "error_passive":
                client.error_passive = True
                client.deliver(line)
        self._event(kind, peer or "*")

    def _event(self, kind: str, peer: str, **detail: object) -> None:
        event = {"source": "can-hub", "kind": kind, "peer": peer, "t": time.time(), **detail}
        log.info("can-hub event %s", event)
        if self.on_event is not None:
            try:
                self.on_event(event)
            except Exception:  # an observer must not stop the bus
                log.exception("can-hub on_event hook failed")

    # --- one client -------------------------------------------------------------------------
    async def _serve_client(self, reader: asyncio.StreamReader,
                            writer: asyncio.StreamWriter) -> None:
        sock = writer.get_extra_info("socket")
        if sock is not None:
            # Each frame is a tiny write; without NODELAY Nagle holds it behind the previous one.
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        host, port = writer.get_extra_info("peername")[:2]
        client = _Client(f"{host}:{port}", writer)
        self._clients[client.name] = client
        writer.write(b"< hi >")
        buffer = b""
        try:
            while chunk := await reader.read(4096):
                buffer += chunk
                while (end := buffer.find(b">")) >= 0:
                    message, buffer = buffer[:end + 1], buffer[end + 1:]
                    self._handle(client, message)
                if len(buffer) > MAX_LINE:   # garbage without a closing '>'
                    log.warning("can-hub %s: dropped %d bytes without '>'", client.name, len(buffer))
                    buffer = b""
        except (ConnectionError, asyncio.CancelledError):
            pass
        finally:
            self._clients.pop(client.name, None)
            writer.close()
            if client.channel:   # a port probe that never opened a channel is not news
                self._event("disconnect", client.name)

    def _handle(self, client: _Client, message: bytes) -> None:
        start = message.find(b"<")
        words = message[start + 1:-1].decode("ascii", "replace").split() if start >= 0 else []
        if not words:
            return
        command = words[0]
        if command == "send" and client.raw:
            self._forward(client, words[1:])
        elif command == "open" and len(words) == 2:
            client.channel = words[1]
            client.writer.write(b"< ok >")
            self._event("connect", client.name, channel=client.channel)
        elif command == "rawmode" and client.channel:
            client.writer.write(b"< ok >")
            client.raw = True
            assert self._loop is not None
            self._loop.call_later(self.join_delay_s, self._release_held, client)
        elif command == "echo":
            client.writer.write(b"< echo >")
        else:
            # Never answer "< error ... >": python-can would parse it as an error frame.
            log.warning("can-hub %s: ignored %r", client.name, message)

    def _release_held(self, client: _Client) -> None:
        held, client.held = client.held or [], None
        if held and not client.bus_off:
            client.writer.write(b"".join(held))

    def _forward(self, sender: _Client, fields: list[str]) -> None:
        try:
            can_id, length = fields[0], int(fields[1], 16)
            data = bytes(int(b, 16) for b in fields[2:2 + length])
            if len(can_id) not in (3, 8) or length != len(data) or length > 8:
                raise ValueError("bad length")
            int(can_id, 16)
        except (ValueError, IndexError):
            log.warning("can-hub %s: malformed send %r", sender.name, fields)
            return
        self.frames_in += 1
        if sender.bus_off:
            return
        line = f"< frame {can_id.upper()} {time.time():.6f} {data.hex().upper()} >".encode()
        for client in self._clients.values():
            if client is not sender and client.channel == sender.channel:
                self.frames_out += client.deliver(line)


def _error_line(error_id: int) -> bytes:
    """An error frame in socketcand's rawmode form; python-can keeps only the identifier."""
    return f"< error {error_id:08X} {time.time():.6f} 0000000000000000 >".encode()
