"""The C side of benchmarks/gateway_latency.py (gateway/loopback.py builds it): its libmodbus server and
client build and talk to the gateway."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from pymodbus.client import ModbusTcpClient

from gateway import loopback
from gateway.transports.modbus_tcp import ModbusTcpTransport
from tests.conftest import require_tool
from tests.gateway.contract import build_gateway

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def harness(tmp_path_factory):
    require_tool("gcc", "apt-get install -y gcc")
    require_tool("libmodbus", "apt-get install -y pkg-config libmodbus-dev",
                 found=shutil.which("pkg-config") is not None
                 and subprocess.run(["pkg-config", "--exists", "libmodbus"]).returncode == 0)
    return loopback, loopback.build_c_harness(ROOT / "benchmarks" / "c", tmp_path_factory.mktemp("c"))


@pytest.fixture(scope="module")
def gateway():
    gw = build_gateway()
    gw.transport = ModbusTcpTransport(gw.devices.values(), port=0)
    gw.transport.start()
    yield gw
    gw.transport.stop()


@pytest.fixture
def c_server(harness):
    bench, exe = harness
    port = bench.free_port()
    proc = subprocess.Popen([str(exe["modbus_server"]), "127.0.0.1", str(port), "20", "215"],
                            stdout=subprocess.DEVNULL)
    try:
        bench.wait_port(port, timeout=10)
        yield port
    finally:
        proc.terminate()
        proc.wait(5)


def _client(exe, *args: str) -> str:
    p = subprocess.run([str(exe["modbus_client"]), *args], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_c_client_reads_the_gateway_values(harness, gateway):
    _, exe = harness
    dev = gateway.devices["storage_io"]
    out = _client(exe, "-v", "-r", "0", "-n", "10", f"127.0.0.1:{gateway.transport.port}/{dev.unit_id}")
    values = [int(v) for v in out.split(":", 2)[2].split()]
    assert values == dev.read_registers("input", 0, 10)


def test_c_server_answers_reads_and_writes(harness, c_server):
    _, exe = harness
    assert _client(exe, "-v", "-r", "0", "-n", "3", f"127.0.0.1:{c_server}/5").split()[1:] == ["215"] * 3
    client = ModbusTcpClient("127.0.0.1", port=c_server, timeout=2)
    assert client.connect()
    assert not client.write_register(1, 4321, device_id=5).isError()  # FC6
    client.close()
    out = _client(exe, "-v", "-r", "0", "-f", "3", "-n", "3", f"127.0.0.1:{c_server}/5")
    assert out.split()[1:] == ["215", "4321", "215"]


def test_c_client_times_interleaved_rounds(harness, gateway, c_server):
    _, exe = harness
    targets = [f"127.0.0.1:{gateway.transport.port}/5", f"127.0.0.1:{c_server}/5"]
    rows = [line.split() for line in _client(exe, "-r", "20", "-w", "2", *targets).splitlines()]
    assert len(rows) == 20 and all(len(r) == 2 and min(map(int, r)) > 0 for r in rows)


def test_pinning_moves_every_thread(harness, gateway):
    bench, _ = harness
    cpus = os.sched_getaffinity(0)
    bench.pin(os.getpid(), {min(cpus)})
    try:
        masks = []
        for tid in os.listdir(f"/proc/{os.getpid()}/task"):
            try:
                masks.append(os.sched_getaffinity(int(tid)))
            except ProcessLookupError:  # a thread that just ended
                pass
        assert len(masks) > 1  # the server thread at least
        assert all(m == {min(cpus)} for m in masks)
    finally:
        bench.pin(os.getpid(), cpus)
