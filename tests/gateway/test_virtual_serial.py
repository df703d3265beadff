"""VirtualSerialPair: bytes pass both ways unchanged, large frames arrive whole, close() frees all."""
from __future__ import annotations

import os
import threading

import pytest
import serial

from gateway.transports.virtual_serial import VirtualSerialPair
from plant.errors import TransportError


def _open(path: str) -> serial.Serial:
    return serial.Serial(path, 19200, timeout=2)


def _open_fds() -> set[str]:
    return set(os.listdir("/proc/self/fd"))


def test_bytes_flow_both_ways_unchanged():
    with VirtualSerialPair() as pair:
        server, client = _open(pair.server_path), _open(pair.client_path)
        request = bytes([0x05, 0x04, 0x00, 0x00, 0x00, 0x0A, 0x70, 0x49])
        client.write(request)
        assert server.read(len(request)) == request
        every_byte = bytes(range(256))  # CR, XON/XOFF, ^C: no line discipline in the way
        server.write(every_byte)
        assert client.read(256) == every_byte
        server.close()
        client.close()


def test_large_frames_arrive_whole_while_both_sides_write():
    blob = os.urandom(200_000)  # far beyond a pty's buffer: the relay must hold back, not drop
    with VirtualSerialPair() as pair:
        server, client = _open(pair.server_path), _open(pair.client_path)
        # writers in threads: a full pty blocks its writer until the other side reads
        writers = [threading.Thread(target=client.write, args=(blob,)),
                   threading.Thread(target=server.write, args=(blob[::-1],))]
        for w in writers:
            w.start()
        back = client.read(len(blob))
        got = server.read(len(blob))
        for w in writers:
            w.join(10)
        assert got == blob and back == blob[::-1]
        server.close()
        client.close()


def test_a_port_can_be_closed_and_reopened():
    with VirtualSerialPair() as pair:
        _open(pair.server_path).close()
        server, client = _open(pair.server_path), _open(pair.client_path)
        client.write(b"again")
        assert server.read(5) == b"again"
        server.close()
        client.close()


def test_close_ends_the_thread_and_frees_the_descriptors():
    before = _open_fds()
    pair = VirtualSerialPair().start()
    assert pair.running and len(_open_fds() - before) >= 6  # 2 masters, 2 slaves, the wake pipe
    thread = pair._thread
    pair.close()
    assert not thread.is_alive() and not pair.running
    assert _open_fds() - before == set()
    pair.close()  # idempotent


def test_links_point_at_the_ends_and_go_away(tmp_path):
    with VirtualSerialPair(tmp_path / "tty") as pair:
        assert os.path.realpath(tmp_path / "tty" / "server") == pair.server_path
        assert os.path.realpath(tmp_path / "tty" / "client") == pair.client_path
        server, client = _open(str(tmp_path / "tty" / "server")), _open(str(tmp_path / "tty" / "client"))
        server.write(b"x")
        assert client.read(1) == b"x"
        server.close()
        client.close()
    assert not os.path.lexists(tmp_path / "tty" / "server")


def test_a_file_in_place_of_a_link_is_refused_and_nothing_leaks(tmp_path):
    (tmp_path / "server").write_text("mine")
    before = _open_fds()
    with pytest.raises(TransportError, match="server: exists and is not a symlink"):
        VirtualSerialPair(tmp_path).start()
    assert _open_fds() - before == set()
    assert (tmp_path / "server").read_text() == "mine"
