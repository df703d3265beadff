"""TrafficLog: malformed frames and refused connections, counted per client and kind, logged a few at a time.

A misbehaving client can send garbage as fast as the link allows; logging each frame would fill a
disk. Every malformed frame is counted (per client and kind, and passed on as an audit event), but
only `examples` of them per client per `window_s` are logged, with their first bytes in hex; at
the end of a window that dropped some, and on `flush()`, one summary line gives the counts. So a
flood gives at most examples + 1 log lines per client per minute.

`mbap_frame` cuts the next frame off a Modbus TCP receive buffer and tells what is wrong with it,
before pymodbus sees it: pymodbus's framer cannot resynchronise after a bad header and logs every
retry. `quiet_pymodbus` filters pymodbus's own per-frame log lines, which these counts replace.
"""
from __future__ import annotations

import logging
import threading
import time
from collections import Counter
from collections.abc import Callable, Container
from typing import Any

#: the longest Modbus TCP length field: unit id + a 253-byte PDU (Modbus Application Protocol §4.1).
MBAP_LENGTH_MAX = 254


def mbap_frame(data: bytes, functions: Container[int]) -> tuple[str | None, int]:
    """(problem, size) of the Modbus TCP frame at the start of `data`: problem None = well formed
    so far (`functions` are the function codes the server decodes); size 0 = wait for more bytes.

    The length field delimits a frame with a bad protocol id; after a bad length there is no way
    back into step, so the whole buffer goes.
    """
    if len(data) < 8:   # MBAP header, unit id, function code
        return None, 0
    length = (data[4] << 8) | data[5]
    if length > MBAP_LENGTH_MAX:
        return "bad MBAP length (too long)", len(data)
    size = 6 + length
    if data[2] or data[3]:
        return "bad protocol id", min(size, len(data))
    if length < 2:
        return "bad MBAP length (too short)", size
    if len(data) < size:
        return None, 0
    fc = data[7]
    if fc == 0 or fc & 0x80:
        return "invalid function code", size
    if fc not in functions:
        return "unknown function code", size
    return None, size


class _PymodbusLog(logging.Filter):
    """pymodbus logs each frame it cannot decode; those are counted by TrafficLog instead. Its
    other records pass, at most 10 a minute, without the hex dump of the last 20 frames that
    pymodbus appends to each error (a client closing before its answer gives one each)."""

    COUNTED = ("Unable to decode frame", "Invalid Modbus protocol id", "Repeating....")

    def __init__(self) -> None:
        super().__init__()
        self.window, self.passed = 0.0, 0

    def filter(self, record: logging.LogRecord) -> bool:
        if str(record.msg).startswith(self.COUNTED):
            return False
        now = time.monotonic()
        if now - self.window >= 60.0:
            self.window, self.passed = now, 0
        self.passed += 1
        if self.passed > 10:
            return False
        record.msg, record.args = record.getMessage().split("\n", 1)[0], ()
        return True


def quiet_pymodbus() -> None:
    """Install the filter on pymodbus's one logger (pymodbus.logging.Log logs only there); once."""
    logger = logging.getLogger("pymodbus.logging")
    if not any(isinstance(f, _PymodbusLog) for f in logger.filters):
        logger.addFilter(_PymodbusLog())


class TrafficLog:
    """Malformed frames and refused or idle-closed connections of one transport; thread-safe.

    `malformed(client, kind, frame)` counts one frame, `connection(client, event)` one refused or
    closed connection (logged once a minute per event). `client` names the host (an IP, not
    IP:port), so reconnecting does not make a new client. `on_event(dict)` receives
    {"kind": "malformed", "transport", "client", "reason"} per frame and {"kind": "link",
    "transport", "client", "event"} per connection (the controller audit).
    """

    def __init__(self, transport: str, logger: logging.Logger, *, examples: int = 3,
                 window_s: float = 60.0, on_event: Callable[[dict], Any] | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.transport, self.log, self.examples, self.window_s = transport, logger, examples, window_s
        self.on_event, self.clock = on_event, clock
        self.counts: Counter = Counter()                 # (client, kind) -> frames
        self.connections: Counter = Counter()            # event -> connections
        self._window: dict[str, tuple[float, int]] = {}  # client -> (window start, examples logged)
        self._dropped: dict[str, Counter] = {}           # client -> kind -> frames not logged
        self._said: dict[str, float] = {}                # connection event -> last logged
        self._lock = threading.Lock()

    def malformed(self, client: str, kind: str, frame: bytes = b"") -> None:
        now = self.clock()
        with self._lock:
            self.counts[(client, kind)] += 1
            start, logged = self._window.get(client, (now, 0))
            if now - start >= self.window_s:
                self._summary(client, now - start)
                start, logged = now, 0
            if logged < self.examples:
                self.log.warning("%s %s: malformed frame (%s): %s%s", self.transport, client, kind,
                                 frame[:32].hex(" "), " ..." if len(frame) > 32 else "")
                logged += 1
            else:
                self._dropped.setdefault(client, Counter())[kind] += 1
            self._window[client] = (start, logged)
        if self.on_event is not None:
            self.on_event({"kind": "malformed", "transport": self.transport, "client": client,
                           "reason": kind})

    def connection(self, client: str, event: str) -> None:
        now = self.clock()
        with self._lock:
            self.connections[event] += 1
            n = self.connections[event]
            loud = now - self._said.get(event, -self.window_s) >= self.window_s
            if loud:
                self._said[event] = now
        if loud:
            self.log.warning("%s %s: %s (%d so far; logged once a minute)", self.transport, client,
                             event, n)
        if self.on_event is not None:
            self.on_event({"kind": "link", "transport": self.transport, "client": client, "event": event})

    def flush(self) -> None:
        """Summary lines for every client with frames not yet logged (call on stop)."""
        now = self.clock()
        with self._lock:
            for client, (start, _) in list(self._window.items()):
                self._summary(client, now - start)
            self._window.clear()

    def total(self) -> int:
        with self._lock:
            return sum(self.counts.values())

    def _summary(self, client: str, span: float) -> None:
        dropped = self._dropped.pop(client, None)
        if dropped:
            kinds = ", ".join(f"{k} x{n}" for k, n in dropped.most_common())
            self.log.warning("%s %s: %d more malformed frames in %.0f s not logged (%s)",
                             self.transport, client, sum(dropped.values()), span, kinds)
