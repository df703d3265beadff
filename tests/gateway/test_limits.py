"""Modbus TCP limits: connection limit, idle timeout, malformed frames counted and logged briefly.

A real house-1 gateway on loopback, raw sockets as clients (issue 15: a flood of garbage must
give a bounded number of log lines, and idle connections must not lock controllers out).
"""
from __future__ import annotations

import logging
import socket
import struct
import time

import pytest

from gateway.audit import Audit
from gateway.maps import codec
from gateway.transports.modbus_tcp import ModbusTcpTransport
from gateway.transports.traffic_log import TrafficLog, mbap_frame, quiet_pymodbus
from tests.gateway.contract import build_gateway


@pytest.fixture(scope="module")
def gateway():
    return build_gateway()


def serve(gateway, **limits) -> tuple[ModbusTcpTransport, Audit]:
    audit = Audit()
    tr = ModbusTcpTransport(gateway.devices.values(), port=0, on_event=audit.event, **limits)
    tr.start()
    return tr, audit


def connect(tr: ModbusTcpTransport) -> socket.socket:
    s = socket.create_connection(("127.0.0.1", tr.port), timeout=2.0)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def read_request(tid: int, unit: int, address: int = 0, count: int = 1) -> bytes:
    return struct.pack(">HHHBBHH", tid, 0, 6, unit, 4, address, count)


def answer(s: socket.socket, tid: int) -> bytes:
    """The answer with transaction id `tid` (earlier answers, e.g. exceptions, are skipped)."""
    buffer = b""
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        while len(buffer) >= 6 and len(buffer) >= 6 + struct.unpack(">H", buffer[4:6])[0]:
            size = 6 + struct.unpack(">H", buffer[4:6])[0]
            frame, buffer = buffer[:size], buffer[size:]
            if struct.unpack(">H", frame[:2])[0] == tid:
                return frame
        chunk = s.recv(4096)
        if not chunk:
            raise ConnectionError("closed by the server")
        buffer += chunk
    raise TimeoutError(f"no answer with transaction id {tid}")


def closed_by_server(s: socket.socket, timeout: float = 2.0) -> bool:
    s.settimeout(timeout)
    try:
        return s.recv(64) == b""
    except ConnectionResetError:
        return True
    except socket.timeout:
        return False


def test_connection_limit_refuses_one_more_while_the_first_still_work(gateway):
    io = gateway.devices["storage_io"]
    tr, audit = serve(gateway, max_connections=3, idle_timeout=0)
    first = [connect(tr) for _ in range(3)]
    try:
        for i, s in enumerate(first):
            s.sendall(read_request(i + 1, io.unit_id))
            assert len(answer(s, i + 1)) == 11
        extra = connect(tr)
        assert closed_by_server(extra)
        extra.close()
        for i, s in enumerate(first):                        # the first three are unharmed
            s.sendall(read_request(10 + i, io.unit_id))
            assert len(answer(s, 10 + i)) == 11
        first.pop().close()                                  # a freed place is usable again
        time.sleep(0.1)
        again = connect(tr)
        first.append(again)
        again.sendall(read_request(20, io.unit_id))
        assert len(answer(again, 20)) == 11
        assert tr.traffic.connections == {"connection refused (limit 3)": 1}
        assert audit.report()["link_events"] == {"modbus-tcp:127.0.0.1 connection refused (limit 3)": 1}
    finally:
        for s in first:
            s.close()
        tr.stop()


@pytest.mark.realtime
def test_idle_timeout_closes_a_silent_connection_only(gateway):
    io = gateway.devices["storage_io"]
    tr, audit = serve(gateway, idle_timeout=0.3)
    silent, busy = connect(tr), connect(tr)
    try:
        for i in range(8):                                   # 0.8 s of polling every 0.1 s
            busy.sendall(read_request(i + 1, io.unit_id))
            assert len(answer(busy, i + 1)) == 11
            time.sleep(0.1)
        assert closed_by_server(silent, timeout=1.0)
        busy.sendall(read_request(99, io.unit_id))
        assert len(answer(busy, 99)) == 11
        assert tr.traffic.connections == {"connection closed (idle 0.3 s)": 1}
    finally:
        silent.close()
        busy.close()
        tr.stop()


#: (kind, frame) of the flood; unit 0x42 is no device of house 1, so nothing answers those.
def flood_frames(unit: int) -> list[tuple[str, bytes]]:
    return [
        ("bad protocol id", struct.pack(">HHHBBHH", 7, 1, 6, unit, 3, 0, 1)),
        ("bad MBAP length (too short)", struct.pack(">HHHB", 7, 0, 1, unit)),
        ("unknown function code", struct.pack(">HHHBB", 7, 0, 2, unit, 0x41)),
        ("invalid function code", struct.pack(">HHHBBB", 7, 0, 3, 0x42, 0x90, 2)),
        ("undecodable PDU", struct.pack(">HHHBBB", 7, 0, 3, 0x42, 3, 0)),
    ]


def test_malformed_flood_is_counted_and_logged_in_a_few_lines(gateway, caplog):
    io = gateway.devices["storage_io"]
    point = io.map.point("t_storage_1")
    tr, audit = serve(gateway)
    kinds = flood_frames(io.unit_id)
    n = 2000
    caplog.set_level(logging.WARNING)
    s = connect(tr)
    try:
        for i in range(n):
            s.sendall(kinds[i % len(kinds)][1])
        s.sendall(read_request(4242, io.unit_id))            # served after the flood, in order
        frame = answer(s, 4242)
        assert list(struct.unpack(">H", frame[9:11])) == codec.to_registers(point, io.read_point("t_storage_1"))
        s.sendall(struct.pack(">HHHBB", 8, 0, 999, io.unit_id, 3) + b"\0" * 40)   # no way back
        s.sendall(read_request(4243, io.unit_id))
        s.close()
        s = connect(tr)                                      # a fresh connection is served
        s.sendall(read_request(4244, io.unit_id))
        assert len(answer(s, 4244)) == 11
    finally:
        s.close()
        tr.stop()
    expected = {kind: n // len(kinds) for kind, _ in kinds}
    expected["bad MBAP length (too long)"] = 1
    assert audit.report()["malformed_frames"] == {"modbus-tcp:127.0.0.1": expected}
    assert tr.traffic.total() == n + 1
    lines = [r for r in caplog.records if r.name.startswith(("pymodbus", "gateway"))]
    assert 1 <= len(lines) <= 5, [r.getMessage() for r in lines]   # 3 examples + 1 summary
    assert "not logged" in lines[-1].getMessage()
    assert "Malformed frames from modbus-tcp:127.0.0.1: 2001".lower() in audit.text().lower()


def test_traffic_log_logs_a_few_examples_a_minute_then_a_summary(caplog):
    now = [0.0]
    traffic = TrafficLog("modbus-tcp", logging.getLogger("test_limits"), clock=lambda: now[0])
    caplog.set_level(logging.WARNING)
    for minute in range(3):
        for _ in range(1000):
            traffic.malformed("10.0.0.9", "bad protocol id", b"\x00" * 40)
            now[0] += 0.05
        now[0] = 60.0 * (minute + 1)
    traffic.flush()
    messages = [r.getMessage() for r in caplog.records]
    assert len(messages) == 3 * 4                       # per minute: 3 examples and one summary
    assert messages[3].startswith("modbus-tcp 10.0.0.9: 997 more malformed frames in")
    assert traffic.counts[("10.0.0.9", "bad protocol id")] == 3000


@pytest.mark.parametrize("frame, expected", [
    (b"\x00\x01\x00\x00\x00\x06\x01\x03", (None, 0)),                  # header complete, body not
    (b"\x00\x01\x00\x00\x00\x06\x01\x03\x00\x00\x00\x01", (None, 12)),
    (b"\x00\x01\x00\x07\x00\x06\x01\x03\x00", ("bad protocol id", 9)),  # cut at what is there
    (b"\x00\x01\x00\x00\x01\x00\x01\x03", ("bad MBAP length (too long)", 8)),
    (b"\x00\x01\x00\x00\x00\x02\x01\x64", ("unknown function code", 8)),
    (b"\x00\x01\x00\x00", (None, 0)),
])
def test_mbap_frame_cuts_and_judges_one_frame(frame, expected):
    assert mbap_frame(frame, {3, 4, 6}) == expected


def test_pymodbus_log_keeps_one_line_per_record_and_ten_a_minute():
    quiet_pymodbus()
    logger = logging.getLogger("pymodbus.logging")
    passed = []
    for i in range(15):
        record = logger.makeRecord("pymodbus.logging", logging.ERROR, __file__, 1,
                                   "Cancel send, because not connected!\n>>>>> send: 0x0 0x1", (), None)
        if all(f.filter(record) for f in logger.filters):
            passed.append(record.getMessage())
    decode = logger.makeRecord("pymodbus.logging", logging.WARNING, __file__, 1,
                               "Unable to decode frame %s", ("x",), None)
    assert not all(f.filter(decode) for f in logger.filters)      # counted by TrafficLog instead
    assert 1 <= len(passed) <= 10 and all("\n" not in m for m in passed)
