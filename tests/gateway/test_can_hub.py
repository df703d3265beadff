"""The socketcand-speaking CAN hub and the bus-spec adapter, driven by python-can's own client."""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import can
import pytest

from gateway.transports.can_bus import (BusSpec, error_message, fault_kind, open_bus,
                                        parse_bus_spec)
from gateway.transports.can_hub import CanHub
from plant.errors import TransportError

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def hub():
    events: list[dict] = []
    server = CanHub(port=0, on_event=events.append).start()
    server.events = events
    yield server
    server.stop()


@pytest.fixture
def pair(hub):
    a, b = open_bus(hub.spec), open_bus(hub.spec)
    assert hub.wait_for_peers(2)
    yield a, b
    a.shutdown()
    b.shutdown()


def frame(can_id: int, data: bytes, extended: bool = False) -> can.Message:
    return can.Message(arbitration_id=can_id, data=data, is_extended_id=extended)


def test_frames_reach_the_other_client_but_not_the_sender(pair):
    a, b = pair
    a.send(frame(0x601, bytes([0x40, 0x00, 0x10, 0, 0, 0, 0, 0])))
    b.send(frame(0x18FF0011, b"\x01\xff", extended=True))
    got_b = b.recv(1.0)
    got_a = a.recv(1.0)
    assert (got_b.arbitration_id, bytes(got_b.data), got_b.is_extended_id) == \
        (0x601, bytes([0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), False)
    assert (got_a.arbitration_id, bytes(got_a.data), got_a.is_extended_id) == \
        (0x18FF0011, b"\x01\xff", True)
    assert a.recv(0.05) is None and b.recv(0.05) is None   # no echo of own frames


@pytest.mark.realtime
def test_round_trip_has_no_nagle_tails(pair):
    a, b = pair
    times = []
    for i in range(100):
        start = time.perf_counter()
        a.send(frame(0x200 + i % 8, bytes([i])))
        assert b.recv(1.0).data[0] == i
        b.send(frame(0x180, bytes([i])))
        assert a.recv(1.0).data[0] == i
        times.append(time.perf_counter() - start)
    median_ms = statistics.median(times) * 1e3
    print(f"hub round trip median {median_ms:.3f} ms, max {max(times) * 1e3:.3f} ms")
    # Loopback with tcp_tune measures ~0.3 ms; 20 ms catches a lost TCP_NODELAY (40 ms tails).
    assert median_ms < 20


def test_channels_are_separate_buses(hub):
    a = open_bus(hub.spec)
    other = open_bus(f"socketcand:127.0.0.1:{hub.port}:can1")
    b = open_bus(hub.spec)
    try:
        assert hub.wait_for_peers(3)
        a.send(frame(0x123, b"\x01"))
        assert b.recv(1.0).arbitration_id == 0x123
        assert other.recv(0.05) is None
    finally:
        for bus in (a, other, b):
            bus.shutdown()


def test_a_client_in_another_process_exchanges_frames(hub):
    echo = textwrap.dedent(f"""
        import can
        from gateway.transports.can_bus import open_bus
        bus = open_bus({hub.spec!r})
        bus.send(can.Message(arbitration_id=0x700 + 0x11, data=b"\\x00", is_extended_id=False))
        msg = bus.recv(5.0)
        bus.send(can.Message(arbitration_id=0x5A0, data=bytes(msg.data)[::-1], is_extended_id=False))
        bus.shutdown()
    """)
    bus = open_bus(hub.spec)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    child = subprocess.Popen([sys.executable, "-c", echo], cwd=REPO, env=env)
    try:
        boot = bus.recv(10.0)      # the child announces itself once connected
        assert boot is not None and boot.arbitration_id == 0x711
        bus.send(frame(0x620, b"\x01\x02\x03"))
        reply = bus.recv(5.0)
        assert reply.arbitration_id == 0x5A0 and bytes(reply.data) == b"\x03\x02\x01"
        assert child.wait(10) == 0
    finally:
        child.kill()
        bus.shutdown()


def test_injected_faults_reach_clients_as_error_frames_and_bus_off_silences(hub, pair):
    a, b = pair
    hub.inject("error_frame")
    assert fault_kind(a.recv(1.0)) == "error_frame"
    assert fault_kind(b.recv(1.0)) == "error_frame"

    victim = hub.peers()[1]   # b connected second
    hub.inject("bus_off", victim)
    assert fault_kind(b.recv(1.0)) == "bus_off"
    a.send(frame(0x181, b"\x01"))
    b.send(frame(0x182, b"\x02"))
    assert b.recv(0.1) is None and a.recv(0.1) is None   # silent both ways

    hub.inject("recover", victim)
    assert fault_kind(b.recv(1.0)) == "recover"
    a.send(frame(0x181, b"\x03"))
    assert bytes(b.recv(1.0).data) == b"\x03"

    hub.inject("error_passive", victim)
    assert fault_kind(b.recv(1.0)) == "error_passive"
    b.send(frame(0x183, b"\x04"))       # error-passive still transmits
    assert bytes(a.recv(1.0).data) == b"\x04"

    kinds = [(e["kind"], e["peer"]) for e in hub.events if e["kind"] not in ("connect",)]
    assert kinds == [("error_frame", "*"), ("bus_off", victim), ("recover", victim),
                     ("error_passive", victim)]
    with pytest.raises(TransportError, match="unknown fault"):
        hub.inject("melt")
    with pytest.raises(TransportError, match="no client"):
        hub.inject("bus_off", "10.0.0.1:1")


def test_error_frames_travel_on_the_virtual_bus_too():
    a = open_bus("virtual:test_can_hub_error_frames")
    b = open_bus("virtual:test_can_hub_error_frames")
    try:
        a.send(error_message("bus_off"))
        assert fault_kind(b.recv(1.0)) == "bus_off"
    finally:
        a.shutdown()
        b.shutdown()


def test_bus_specs_parse_and_bad_ones_say_how_to_fix():
    assert parse_bus_spec("virtual:house1") == BusSpec("virtual", "house1")
    assert parse_bus_spec("socketcand:127.0.0.1:29536") == \
        BusSpec("socketcand", "can0", "127.0.0.1", 29536)
    assert str(parse_bus_spec("socketcand:localhost:1:vcan1")) == "socketcand:localhost:1:vcan1"
    assert parse_bus_spec("socketcan:can0") == BusSpec("socketcan", "can0")
    for bad in ("", "virtual:", "pcan:PCAN_USBBUS1", "socketcand:127.0.0.1", "socketcand:h:x"):
        with pytest.raises(TransportError, match="CAN bus spec"):
            parse_bus_spec(bad)


def test_socketcand_without_a_hub_fails_fast_with_the_fix(hub):
    port = hub.port
    hub.stop()
    start = time.monotonic()
    with pytest.raises(TransportError, match="twin can-hub"):
        open_bus(f"socketcand:127.0.0.1:{port}:can0")
    assert time.monotonic() - start < 3


def test_cli_serves_a_hub_until_interrupted():
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    child = subprocess.Popen([sys.executable, "-m", "cli.main", "can-hub", "--port", "0"],
                             cwd=REPO, env=env, stdout=subprocess.PIPE, text=True)
    try:
        line = child.stdout.readline()
        assert "listening on 127.0.0.1:" in line
        spec = line.split("bus spec ")[1].strip()
        a, b = open_bus(spec), open_bus(spec)
        a.send(frame(0x77, b"\x07"))
        assert bytes(b.recv(2.0).data) == b"\x07"
        a.shutdown()
        b.shutdown()
        assert '"kind": "connect"' in child.stdout.readline()
    finally:
        child.terminate()
        child.wait(5)
