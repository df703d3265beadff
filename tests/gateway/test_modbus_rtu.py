"""Modbus RTU over a socat pty pair: the device contract, plus the corrupted-CRC link fault."""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time

import pytest
from pymodbus.client import ModbusSerialClient

from gateway.transports.modbus_rtu import ModbusRtuTransport
from tests.gateway.contract import TIMEOUT, ClientBus, DeviceContract, build_gateway

pytestmark = pytest.mark.skipif(shutil.which("socat") is None,
                                reason="socat not installed (needed for the pty pair)")


@pytest.fixture(scope="module")
def pty_pair():
    """Two linked pseudo-terminals: the server opens one end, the client the other."""
    tmp = tempfile.mkdtemp(prefix="twin-rtu-")
    a, b = os.path.join(tmp, "server"), os.path.join(tmp, "client")
    proc = subprocess.Popen(["socat", f"pty,raw,echo=0,link={a}", f"pty,raw,echo=0,link={b}"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(100):
        if os.path.exists(a) and os.path.exists(b):
            break
        time.sleep(0.02)
    yield a, b
    proc.terminate()
    proc.wait(5)


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
