"""A district across two hosts: host B is a network namespace with its own address, joined to host A
by a veth pair; B's house reaches A's broker only by A's address and is reached back at its own
(docs/district.md, "Launch across two hosts")."""
import os
import subprocess
import sys

import pytest

from profiles.recording import read_recording
from tests.conftest import require_tool

from .test_federation import district_file

DAYS = 0.1


def sh(*cmd: str) -> None:
    subprocess.run(cmd, check=True, capture_output=True)


@pytest.fixture
def host_b():
    require_tool("ip", "apt-get install iproute2")
    if os.geteuid() != 0:
        pytest.skip("network namespaces need root (the test makes host B with `ip netns add`)")
    ns, a, b = f"twinB{os.getpid()}", f"vA{os.getpid()}", f"vB{os.getpid()}"
    sh("ip", "netns", "add", ns)
    try:
        sh("ip", "link", "add", a, "type", "veth", "peer", "name", b)
        sh("ip", "link", "set", b, "netns", ns)
        sh("ip", "addr", "add", "10.77.0.1/24", "dev", a)
        sh("ip", "link", "set", a, "up")
        sh("ip", "netns", "exec", ns, "ip", "addr", "add", "10.77.0.2/24", "dev", b)
        sh("ip", "netns", "exec", ns, "ip", "link", "set", b, "up")
        sh("ip", "netns", "exec", ns, "ip", "link", "set", "lo", "up")
        yield ns
    finally:
        subprocess.run(["ip", "link", "del", a], capture_output=True)
        subprocess.run(["ip", "netns", "del", ns], capture_output=True)


def test_a_house_on_host_b_joins_the_broker_on_host_a(tmp_path, host_b):
    path = district_file(tmp_path, {"house1": "rules", "house2": "rules"})
    twin = [sys.executable, "-m", "cli.main", "district"]
    a = subprocess.Popen(twin + ["run", path, "--days", str(DAYS), "--out", str(tmp_path / "a"), "--only",
                                 "grid,house1", "--listen", "10.77.0.1", "--broker-port", "23500",
                                 "--interface", "10.77.0.1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    b = subprocess.run(["ip", "netns", "exec", host_b] + twin + ["join", path, "--broker", "tcp://10.77.0.1:23500",
                        "--interface", "10.77.0.2", "--only", "house2", "--days", str(DAYS),
                        "--out", str(tmp_path / "b")], capture_output=True, text=True, timeout=180)
    out_a, err_a = a.communicate(timeout=60)
    assert b.returncode == 0, b.stderr
    assert a.returncode == 0, err_a
    assert "broker tcp://10.77.0.1:23500" in out_a
    steps = int(DAYS * 86400 / 60)
    for folder, member in (("a", "grid"), ("a", "house1"), ("b", "house2")):
        assert len(read_recording(tmp_path / folder / member).time) == steps + 1
