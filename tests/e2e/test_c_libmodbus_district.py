"""The C libmodbus controller runs house 1 of a running district (`twin district serve`, paced)
while house 2 runs its built-in controllers; both houses and the grid are their own processes."""
import subprocess

import numpy as np
import pytest

from district.federation.engine import free_port
from profiles.recording import read_recording

from tests.district.serving import serve

from .test_c_libmodbus import build_tools, controller_bin  # noqa: F401 (fixtures: build the example)

# What is tested is the controller's scans and writes through a paced district, not the pace: the
# district steps 60 s at a time (125 ms of wall time a step at 480x, each house's step well under
# 10 ms) and the controller's scan takes a few ms of its 125 ms period
SPEED = 480.0       # simulated seconds per wall second
DAYS = 0.05         # 72 min: 9 s of wall time
PERIOD_MS = 125     # the controller scans every 60 simulated seconds
MARGIN_S = 3.0      # wall seconds the controller stops before the district does


@pytest.mark.realtime
def test_c_controller_runs_one_house_of_a_district(tmp_path, controller_bin):  # noqa: F811
    p1, p2 = free_port(), free_port()
    twin, out = serve(tmp_path, f"""
[district]
name = "cdistrict"
step = 60.0
[plant]
node = "plant"
[pipes.p1]
from = "plant"
to = "n1"
[pipes.p2]
from = "n1"
to = "n2"
[houses.house1]
node = "n1"
controller = "external"
modbus_port = {p1}
overrides = {{ "storage.T_init_top" = 62.0 }}   # below the controller's CHP threshold of 65 degC
[houses.house2]
node = "n2"
modbus_port = {p2}
""", DAYS, SPEED)
    assert f"serving modbus-tcp 127.0.0.1:{p1}" in (out / "logs" / "house1.log").read_text()
    scans = int(DAYS * 86400 / 60) - round(MARGIN_S * 1000 / PERIOD_MS)     # stop before the district does
    ctl = subprocess.run([str(controller_bin), "-p", str(p1), "--period", str(PERIOD_MS), "--cycles", str(scans)],
                         capture_output=True, text=True, timeout=120)
    stdout, stderr = twin.communicate(timeout=120)
    assert ctl.returncode == 0, ctl.stdout + ctl.stderr
    assert twin.returncode == 0, stderr
    assert f"house1: node n1, modbus-tcp 127.0.0.1:{p1}" in stdout and "controller external" in stdout
    lines = ctl.stdout.splitlines()
    assert len(lines) == scans and not any("link=down" in line for line in lines)
    assert "chp=1" in lines[0]                              # 62 degC at the top: the CHP is asked to run

    h1 = read_recording(out / "house1")
    writes = [e for e in h1.events if e["kind"] == "write"]
    assert {e["point"] for e in writes} >= {"run_request", "modulation_set", "demand_voltage", "charge_enable"}
    assert all(e["accepted"] == "True" for e in writes)
    on = h1.values[:, h1.names.index("chp.on")]
    P_el = h1.values[:, h1.names.index("chp.P_el")]
    print(f"CHP on {(on == 1.0).sum()} of {len(on)} samples, {len(lines)} scans")
    assert (on == 1.0).sum() > len(on) // 2 and P_el.max() > 1800.0   # the CHP ran on the C controller's command

    h2 = read_recording(out / "house2")                      # house 2 on its own rules, no client
    assert not [e for e in h2.events if e["kind"] == "write"]
    assert h2.values[:, h2.names.index("heat_pump.Q_flow")].max() > 1000.0
    grid = read_recording(out / "grid")
    assert len(grid.time) == int(DAYS * 86400 / 60) + 1 and np.all(np.isfinite(grid.values))
