"""`twin phil compare RUN`: set vs measured per interface, and the run against the same house
simulated alone on the same type day (table and figures in the run directory)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from phil.emulator.server import BenchServer
from phil.loop import PhilLoop
from phil.options import PhilOptions

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.realtime
def test_compare_a_run_with_its_benches_and_the_house_alone(tmp_path):
    # 300x: the compared figures are those of 150x (return follow RMS 0.849 / 0.854 K, radiator
    # heat -8.67 / -8.69 % of the house alone): the 12 min window's, not the pace's
    servers = {n: BenchServer(n, speed=300.0).start() for n in ("space_heating", "tap_water", "solar")}
    try:
        loop = PhilLoop("house1", {n: ("127.0.0.1", s.port) for n, s in servers.items()},
                        PhilOptions(speed=300.0, dt=2.0, hours=0.2, typeday=4, start_h=32.0, warmup_s=60.0,
                                    record=tmp_path / "run"))
        assert loop.run()["stop_reason"] == "end of run"
    finally:
        for s in servers.values():
            s.stop()
    out = subprocess.run([sys.executable, "-m", "cli.main", "phil", "compare", str(tmp_path / "run")],
                         cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    md = (tmp_path / "run" / "compare.md").read_text()
    for row in ("| space_heating | STM_HCRL_Set_degC | STM_HCRL_degC | °C |", "| tap_water | E_DHW_Set_kWh |",
                "| solar | PEH_ST_Set_kW | PEH_ST_kW | kW |", "| heat to the radiators [kWh] |",
                "| room temperature mean [degC] |", "heat per generator [kWh] boiler"):
        assert row in md and row in out.stdout
    for png in ("compare_space_heating.png", "compare_tap_water.png", "compare_solar.png", "compare_house.png"):
        assert (tmp_path / "run" / png).stat().st_size > 10_000
    # the return the bench produced follows the set one within a fraction of a kelvin (RMS)
    line = next(line for line in md.splitlines() if "| STM_HCRL_Set_degC |" in line)
    assert float(line.split("|")[5]) < 1.0
    # the same room with the same heating request: the radiators' heat within 10 % of the house alone
    line = next(line for line in md.splitlines() if "heat to the radiators" in line)
    assert abs(float(line.split("|")[4].split()[0])) < 10.0


def test_compare_refuses_a_run_that_is_not_phil(tmp_path):
    (tmp_path / "signals.csv").write_text("time,a\n0,1\n")
    (tmp_path / "meta.json").write_text('{"kind": "serve"}')
    (tmp_path / "events.csv").write_text("t,kind\n")
    out = subprocess.run([sys.executable, "-m", "cli.main", "phil", "compare", str(tmp_path)],
                         cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert out.returncode != 0 and "not a PHIL run" in out.stderr + out.stdout
