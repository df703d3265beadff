"""Modbus RTU over a virtual serial pair: the device contract, plus the corrupted-CRC link fault."""
from __future__ import annotations

import re
import subprocess
import sys
import time

import pytest
from pymodbus.client import ModbusSerialClient

from gateway.transports.modbus_rtu import ModbusRtuTransport
from gateway.transports.virtual_serial import VirtualSerialPair
from tests.gateway.contract import TIMEOUT, ClientBus, DeviceContract, build_gateway


@pytest.fixture(scope="module")
def pty_pair():
    """Two linked pseudo-terminals: the server opens one end, the client the other."""
    with VirtualSerialPair() as pair:
        yield pair.server_path, pair.client_path


@pytest.fixture(scope="module")
def rtu_gateway(pty_pair):
    server_end, client_end = pty_pair
    gw = build_gateway()
    gw.transport = ModbusRtuTransport(gw.devices.values(), port=server_end, baudrate=19200,
                                      parity="N")  # a pty rejects parity settings (EINVAL)
    gw.transport.start()
    client = ModbusSerialClient(client_end, baudrate=19200, parity="N", timeout=0.3, retries=0)
    assert client.connect()
    gw.bus = ClientBus(client)
    yield gw
    client.close()
    gw.transport.stop()


@pytest.mark.realtime  # a client that waits 0.3 s for each answer at 19200 baud, no retry
class TestModbusRtu(DeviceContract):
    transport_name = "modbus-rtu"

    @pytest.fixture
    def gateway(self, rtu_gateway):
        return rtu_gateway

    def test_bad_crc_answer_is_rejected_by_master(self, gateway):
        dev = gateway.devices["mixing_station"]
        dev.set_link_fault("bad_crc")
        assert gateway.bus.read(dev.unit_id, "input", 500, 1) == TIMEOUT
        dev.clear_faults()
        time.sleep(0.05)
        assert isinstance(gateway.bus.read(dev.unit_id, "input", 500, 1), list)


def test_virtual_port_serves_on_its_own_pair():
    gw = build_gateway()
    tr = ModbusRtuTransport(gw.devices.values(), port="virtual")
    assert tr.client_path is None
    tr.start()
    try:
        client = ModbusSerialClient(tr.client_path, baudrate=19200, parity="N", timeout=1, retries=0)
        assert client.connect()
        dev = gw.devices["mixing_station"]
        assert isinstance(ClientBus(client).read(dev.unit_id, "input", 500, 1), list)
        client.close()
    finally:
        tr.stop()
    assert not tr._virtual.running


def test_twin_serve_virtual_rtu_prints_a_path_a_master_reads(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "serve", "house1", "--modbus-rtu",
                             "virtual", "--lock-step"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        lines = []
        for line in proc.stdout:  # the path is printed once the server listens
            lines.append(line)
            found = re.search(r"virtual serial port: connect your master to (\S+)", line)
            if found:
                break
        assert found, "".join(lines)
        proc.stdin.write("step 10\n")
        proc.stdin.flush()
        assert proc.stdout.readline().strip() == "t=10"
        client = ModbusSerialClient(found.group(1), baudrate=19200, parity="N", timeout=2, retries=0)
        assert client.connect()
        answer = client.read_input_registers(0, count=2, device_id=5)  # storage I/O: T layers, 0.1 K
        client.close()
        assert not answer.isError() and all(100 < r < 1000 for r in answer.registers), answer
        out, _ = proc.communicate("quit\n", timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, out
    assert "modbus-rtu" in out and "1 requests" in out
