"""Modbus TCP over loopback: the device contract, plus TCP-only behaviour (allow-list, drop, late, mbpoll)."""
from __future__ import annotations

import socket
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


class TestModbusTcp(DeviceContract):
    transport_name = "modbus-tcp"

    @pytest.fixture
    def gateway(self, tcp_gateway):
        return tcp_gateway

    def test_unknown_unit_gets_no_reply(self, gateway):
        assert gateway.bus.read(99, "input", 0, 1) == TIMEOUT

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
