"""c-libmodbus example: warning-free build, one winter day in lock-step, and a gateway restart.

The controller runs as a subprocess with --lockstep: the harness writes one line, the controller
scans once and answers one line, then the harness steps the plant SCAN x 1 s.
"""
import subprocess

import pytest

from profiles.recording import read_recording
from gateway.transports.modbus_tcp import ModbusTcpTransport
from tests.conftest import require_tool

from .conftest import DAY, EXAMPLES, SCAN, check_against_offline, make_runtime, modbus_port, recorded_kpis

SRC = EXAMPLES / "c-libmodbus"


@pytest.fixture(autouse=True, scope="module")
def build_tools():
    for tool in ("gcc", "make", "pkg-config"):
        require_tool(tool, f"apt-get install {tool}")
    require_tool("libmodbus", "apt-get install libmodbus-dev",
                 found=subprocess.run(["pkg-config", "--exists", "libmodbus"]).returncode == 0)


@pytest.fixture(scope="module")
def controller_bin(tmp_path_factory):
    out = tmp_path_factory.mktemp("c") / "controller"
    build = subprocess.run(["make", "-s", "-C", str(SRC), "check", f"OUT={out}"],
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stdout + build.stderr
    assert "warning" not in (build.stdout + build.stderr).lower()   # -Wall -Wextra -Werror
    return out


class Lockstep:
    """The controller process, one scan per request."""

    def __init__(self, binary, port: int):
        self.p = subprocess.Popen([str(binary), "-p", str(port), "--lockstep"], stdin=subprocess.PIPE,
                                  stdout=subprocess.PIPE, text=True, bufsize=1)

    def scan(self) -> str:
        self.p.stdin.write("\n")
        self.p.stdin.flush()
        line = self.p.stdout.readline()
        assert line, f"controller exited with {self.p.wait(5)}"
        return line.strip()

    def finish(self) -> int:
        self.p.stdin.close()
        return self.p.wait(10)


def test_c_controller_one_winter_day_matches_the_built_in_rules(tmp_path, controller_bin, offline_kpis):
    rt = make_runtime(tmp_path / "run")
    with rt:
        ctl = Lockstep(controller_bin, modbus_port(rt))
        try:
            for _ in range(DAY // SCAN):
                line = ctl.scan()
                assert "link=" not in line, line
                rt.clock.step(SCAN)
        finally:
            assert ctl.finish() == 0
    check_against_offline(recorded_kpis(tmp_path / "run"), offline_kpis)


def test_c_controller_survives_a_gateway_restart(tmp_path, controller_bin):
    """Modbus transport down for 6 scans while the CHP runs: the controller reports the link down
    with back-off, drops its outputs to the safe state (generators off, hysteresis forgotten),
    reconnects to the new server and decides afresh: the CHP only runs again if the storage top
    is below 65 degC now. (While the link is down the devices hold the last command until their
    watchdog expires: 600 s CHP, 300 s boiler; the outage here is 120 s.)"""
    rt = make_runtime(tmp_path / "run")
    with rt:
        port = modbus_port(rt)
        ctl = Lockstep(controller_bin, port)
        line = ""
        for _ in range(4 * 3600 // SCAN):         # until the storage has cooled and the CHP runs
            line = ctl.scan()
            rt.clock.step(SCAN)
            if "chp=1" in line:
                break
        assert "chp=1" in line, line
        first = rt.transports.pop()
        first.stop()                              # the gateway's Modbus side goes away
        down = []
        for _ in range(6):
            down.append(ctl.scan())
            rt.clock.step(SCAN)
        restart_t = rt.house.t
        again = ModbusTcpTransport(rt.devices.values(), "127.0.0.1", port)
        again.start()
        rt.transports.append(again)
        up = []
        for _ in range(12):                       # back-off is at most 8 scans
            up.append(ctl.scan())
            rt.clock.step(SCAN)
        assert ctl.finish() == 0
    assert all("link=down" in line and "chp=0 boiler=0 dhw=0" in line for line in down), down
    assert any("back-off" in line for line in down)               # not hammering the dead port
    resumed = [line for line in up if "top=" in line]
    assert resumed, up                                           # reconnected, controlling again
    top = int(resumed[0].split("top=")[1].split()[0])
    assert ("chp=1" in resumed[0]) == (top < 650), resumed[0]    # fresh decision from the safe state
    writes = [e for e in read_recording(tmp_path / "run").events
              if e["kind"] == "write" and float(e["t"]) >= restart_t]
    assert {e["point"] for e in writes} >= {"modulation_set", "run_request", "demand_voltage", "charge_enable"}
    assert all(e["accepted"] == "True" for e in writes)
