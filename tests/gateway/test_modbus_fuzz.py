"""Robustness: ≥10,000 random frames at the Modbus TCP server over raw sockets.

Frames are a mix of well-formed MBAP headers with random PDUs (any function code, address,
count, payload, unit id) and pure garbage. After each batch the plant steps and a proper client
must still get correct answers: the server keeps serving and the plant keeps stepping.
"""
from __future__ import annotations

import socket
import struct

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pymodbus.client import ModbusTcpClient

from gateway.maps import codec
from gateway.transports.modbus_tcp import ModbusTcpTransport
from tests.gateway.contract import build_gateway

BATCH = 50
EXAMPLES = 220                     # 220 x 50 = 11,000 frames generated

units = st.sampled_from([0, 1, 2, 4, 5, 6, 7, 99, 255])
functions = st.sampled_from([1, 2, 3, 4, 5, 6, 7, 8, 11, 15, 16, 17, 20, 22, 23, 43, 0x41, 0x80, 0xFF])
structured = st.builds(
    lambda tid, unit, fc, addr, count, payload, lie: (
        struct.pack(">HHHBB", tid, 0 if lie else 0,
                    (len(payload) + 6 + (lie % 3) - 1) if lie else len(payload) + 6, unit, fc)
        + struct.pack(">HH", addr, count) + payload),
    st.integers(0, 0xFFFF), units, functions, st.integers(0, 0xFFFF),
    st.integers(0, 300), st.binary(max_size=12), st.integers(0, 3))
garbage = st.binary(min_size=1, max_size=40)
frames = st.lists(st.one_of(structured, structured, garbage), min_size=BATCH, max_size=BATCH)


def test_server_survives_random_frames():
    gw = build_gateway()
    tr = ModbusTcpTransport(gw.devices.values(), port=0)
    tr.start()
    sent = {"frames": 0}
    io = gw.devices["storage_io"]
    point = io.map.point("t_storage_1")
    client = ModbusTcpClient("127.0.0.1", port=tr.port, timeout=1.0, retries=1)
    try:
        @settings(max_examples=EXAMPLES, deadline=None, database=None,
                  suppress_health_check=list(HealthCheck))
        @given(frames)
        def batch(frame_list: list[bytes]) -> None:
            with socket.create_connection(("127.0.0.1", tr.port), timeout=1.0) as s:
                s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                for frame in frame_list:
                    try:
                        s.sendall(frame)
                    except OSError:      # server closed this connection: fine, it is garbage
                        break
                    sent["frames"] += 1
            t_before = gw.port.t
            gw.step(5.0)
            assert gw.port.t == t_before + 5.0

        batch()
        assert client.connect()
        r = client.read_input_registers(0, count=1, device_id=io.unit_id)
        assert not r.isError()
        assert r.registers == codec.to_registers(point, io.read_point("t_storage_1"))
        assert sent["frames"] >= 10_000, sent   # counted as delivered; a batch ends early on close
    finally:
        client.close()
        tr.stop()
