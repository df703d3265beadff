"""Modbus TCP over loopback: the device contract, plus TCP-only behaviour (allow-list, drop, late,
mbpoll, pipelined and split frames, exception 0x0B for a unit nothing serves)."""
from __future__ import annotations

import socket
import struct
import subprocess
import time

import pytest
from pymodbus.client import ModbusTcpClient

from gateway.transports.modbus_tcp import ModbusTcpTransport
from tests.conftest import require_tool
from tests.gateway.contract import TIMEOUT, ClientBus, DeviceContract, build_gateway


@pytest.fixture(scope="module")
def tcp_gateway():
    gw = build_gateway()
    gw.transport = ModbusTcpTransport(gw.devices.values(), port=0)
    gw.transport.start()
    client = ModbusTcpClient("127.0.0.1", port=gw.transport.port, timeout=0.3, retries=0)
    assert client.connect()
    gw.bus = ClientBus(client)
    yield gw
    client.close()
    gw.transport.stop()


@pytest.mark.realtime  # a client that waits 0.3 s for each answer, no retry
class TestModbusTcp(DeviceContract):
    transport_name = "modbus-tcp"

    @pytest.fixture
    def gateway(self, tcp_gateway):
        return tcp_gateway

    def test_unknown_unit_gets_gateway_exception(self, gateway):
        assert gateway.bus.read(99, "input", 0, 1) == 0x0B   # gateway target device failed to respond

    def test_late_answer_arrives_after_delay(self, gateway):
        dev = gateway.devices["mixing_station"]
        dev.set_link_fault("late", delay_s=0.15)
        t0 = time.perf_counter()
        assert isinstance(gateway.bus.read(dev.unit_id, "input", 500, 1), list)
        assert time.perf_counter() - t0 >= 0.15

    def test_drop_closes_connection_server_keeps_serving(self, gateway):
        dev = gateway.devices["dhw_station"]
        dev.set_link_fault("drop")
        other = ModbusTcpClient("127.0.0.1", port=gateway.transport.port, timeout=0.3, retries=0)
        assert other.connect()
        assert ClientBus(other).read(dev.unit_id, "input", 0, 1) == TIMEOUT
        other.close()
        dev.clear_faults()
        assert isinstance(gateway.bus.read(dev.unit_id, "input", 0, 1), list)

    def test_client_disconnecting_mid_request_harms_nobody(self, gateway):
        with socket.create_connection(("127.0.0.1", gateway.transport.port)) as s:
            s.sendall(bytes.fromhex("0001000000060104"))   # half a request, then hang up
        assert isinstance(gateway.bus.read(gateway.unit("storage_io"), "input", 0, 2), list)


def test_allow_list_refuses_other_clients():
    gw = build_gateway()
    tr = ModbusTcpTransport(gw.devices.values(), port=0, allow=["10.9.9.9"])
    tr.start()
    try:
        client = ModbusTcpClient("127.0.0.1", port=tr.port, timeout=0.3, retries=0)
        client.connect()
        assert ClientBus(client).read(1, "input", 8014, 1) == TIMEOUT
        client.close()
        assert any(e.get("reason") == "client" for e in gw.events)
    finally:
        tr.stop()


def test_mbpoll_reads_chp_registers(tcp_gateway):
    require_tool("mbpoll", "apt-get install mbpoll")
    gw = tcp_gateway
    out = subprocess.run(
        ["mbpoll", "-m", "tcp", "-a", "1", "-t", "3", "-0", "-r", "8019", "-c", "2", "-1",
         "-p", str(gw.transport.port), "127.0.0.1"],
        capture_output=True, text=True, timeout=20)
    assert out.returncode == 0, out.stdout + out.stderr
    values = dict(line.strip().strip("[").split("]:") for line in out.stdout.splitlines()
                  if line.strip().startswith("[8019]") or line.strip().startswith("[8020]"))
    assert int(values["8019"]) == round(gw.port.get("chp.T_sup") * 10)
    assert int(values["8020"]) == round(gw.port.get("chp.T_ret") * 10)


# --- raw MBAP frames: pipelining, split frames, unknown unit ------------------------------------
def _read_holding(tid: int, unit: int, address: int, count: int) -> bytes:
    """MBAP header (transaction id, protocol 0, length, unit id) + FC3 address count."""
    return struct.pack(">HHHBBHH", tid, 0, 6, unit, 3, address, count)


def _frames(sock: socket.socket, n: int, timeout: float = 2.0) -> list[bytes]:
    """Up to `n` whole MBAP frames, as they arrive, within `timeout` s."""
    buffer, frames, end = b"", [], time.monotonic() + timeout
    while len(frames) < n and time.monotonic() < end:
        while len(buffer) >= 6 and len(buffer) >= 6 + struct.unpack(">H", buffer[4:6])[0]:
            size = 6 + struct.unpack(">H", buffer[4:6])[0]
            frames.append(buffer[:size])
            buffer = buffer[size:]
        if len(frames) >= n:
            break
        sock.settimeout(max(end - time.monotonic(), 0.01))
        try:
            chunk = sock.recv(4096)
        except socket.timeout:
            break
        if not chunk:
            break
        buffer += chunk
    return frames


def _registers(frame: bytes) -> list[int]:
    assert frame[7] == 3 and frame[8] == len(frame) - 9, frame.hex()
    return list(struct.unpack(f">{frame[8] // 2}H", frame[9:]))


def _connect(gateway) -> socket.socket:
    s = socket.create_connection(("127.0.0.1", gateway.transport.port), timeout=2.0)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def _requests(gateway) -> list[tuple[int, int, int]]:
    """(unit, address, count) of three holding-register reads, on three devices."""
    return [(gateway.unit("boiler_wolf_cgb"), 449, 2), (gateway.unit("chp_neotower2"), 8305, 1),
            (gateway.unit("dhw_station"), 10, 1)]


def _expected(gateway, unit: int, address: int, count: int) -> list[int]:
    device = next(d for d in gateway.devices.values() if d.unit_id == unit)
    words = device.read_registers("holding", address, count)
    assert isinstance(words, list), words
    return words


def test_pipelined_requests_in_one_segment_each_answered(tcp_gateway):
    """Three requests in one sendall (Modbus Messaging on TCP/IP §4.2: the MBAP length delimits
    each frame): three answers, each with its own transaction id and its device's registers."""
    gw = tcp_gateway
    reqs = _requests(gw)
    tids = [0x1201, 0x1202, 0x1203]
    with _connect(gw) as s:
        for _ in range(3):   # not only on a fresh connection
            s.sendall(b"".join(_read_holding(t, *r) for t, r in zip(tids, reqs)))
            answers = {struct.unpack(">H", f[:2])[0]: f for f in _frames(s, 3)}
            assert sorted(answers) == tids
            for t, (unit, address, count) in zip(tids, reqs):
                assert answers[t][6] == unit
                assert _registers(answers[t]) == _expected(gw, unit, address, count)
            assert _frames(s, 1, timeout=0.2) == []   # nothing more
            tids = [t + 3 for t in tids]


def test_frame_split_across_segments_answered_once(tcp_gateway):
    gw = tcp_gateway
    (unit, address, count), (unit2, address2, count2) = _requests(gw)[:2]
    with _connect(gw) as s:
        # one request in two segments
        frame = _read_holding(0x2001, unit, address, count)
        s.sendall(frame[:5])
        time.sleep(0.1)
        s.sendall(frame[5:])
        answers = _frames(s, 2, timeout=0.5)
        assert [struct.unpack(">H", f[:2])[0] for f in answers] == [0x2001]
        assert _registers(answers[0]) == _expected(gw, unit, address, count)
        # a whole request and the head of the next in one segment, the tail later
        first, second = _read_holding(0x2002, unit, address, count), _read_holding(0x2003, unit2, address2, count2)
        s.sendall(first + second[:9])
        time.sleep(0.1)
        s.sendall(second[9:])
        answers = _frames(s, 3, timeout=0.5)
        assert sorted(struct.unpack(">H", f[:2])[0] for f in answers) == [0x2002, 0x2003]
        by_tid = {struct.unpack(">H", f[:2])[0]: f for f in answers}
        assert _registers(by_tid[0x2003]) == _expected(gw, unit2, address2, count2)


def test_unserved_unit_gets_exception_0b_and_server_keeps_serving(tcp_gateway):
    gw = tcp_gateway
    assert 0x42 not in {d.unit_id for d in gw.devices.values()}
    unit, address, count = _requests(gw)[0]
    with _connect(gw) as s:
        s.sendall(_read_holding(0x3001, 0x42, 0, 1))
        [answer] = _frames(s, 1)
        tid, proto, length, rx_unit, fc, code = struct.unpack(">HHHBBB", answer)
        assert (tid, proto, length, rx_unit) == (0x3001, 0, 3, 0x42)
        assert fc == 3 | 0x80 and code == 0x0B   # gateway target device failed to respond
        s.sendall(_read_holding(0x3002, unit, address, count))
        [answer] = _frames(s, 1)
        assert struct.unpack(">H", answer[:2])[0] == 0x3002
        assert _registers(answer) == _expected(gw, unit, address, count)
