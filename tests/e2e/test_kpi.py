"""`twin kpi` on real recordings: a lock-step `twin serve --record` run and `twin simulate` CSVs of houses 1, 2, 4."""
import json
import subprocess
import sys

import numpy as np
import pytest

from cli.main import main
from gateway.kpi import kpis, load_series, soc_swings
from plant.errors import ConfigError
from plant.house import load_house

TWIN = [sys.executable, "-m", "cli.main"]


def test_kpi_of_a_serve_recording_table_and_json(tmp_path, capsys):
    rec = tmp_path / "rec"
    served = subprocess.run(TWIN + ["serve", "house1", "--start", "2021-01-15", "--modbus-tcp", "127.0.0.1:0",
                                    "--lock-step", "--built-in-control", "--record", str(rec)],
                            input="step 3600\nquit\n", capture_output=True, text=True, timeout=120)
    assert served.returncode == 0, served.stderr
    assert main(["kpi", str(rec)]) == 0
    text = capsys.readouterr().out
    assert "thermal discomfort" in text and "storage SOC swings" in text
    assert "fuel (chp + boiler)" in text and [line.split()[0] for line in text.splitlines()[-3:]] == [
        "generator", "chp", "boiler"]
    assert main(["kpi", str(rec), "--json"]) == 0
    k = json.loads(capsys.readouterr().out)
    assert k["duration_h"] == pytest.approx(1.0)
    # the recording agrees with the plant's own counters
    t, names, rows = load_series(rec)
    e_fuel = (rows[-1, names.index("chp.E_fuel")] + rows[-1, names.index("boiler.E_fuel")]) / 3.6e6
    assert k["fuel_kWh"] == pytest.approx(e_fuel, rel=1e-3)
    assert k["chp_starts"] == int(rows[-1, names.index("chp.starts")])


def test_kpi_of_a_simulate_csv_matches_the_arrays(tmp_path, capsys):
    csv = tmp_path / "run.csv"
    assert main(["simulate", "house1", "--start", "2021-01-15", "--days", "0.25", "--out-interval", "60",
                 "--out", str(csv), "--no-progress"]) == 0
    capsys.readouterr()
    from_csv = kpis(*load_series(csv))
    house = load_house("house1", start="2021-01-15")
    times, rows = house.run(6 * 3600, dt=1.0, out_interval=60.0)
    direct = kpis(times, house.catalogue.names, rows)
    assert from_csv.heat_boiler_kWh == pytest.approx(direct.heat_boiler_kWh, rel=1e-4)
    assert from_csv.dhw_draws == direct.dhw_draws and from_csv.duration_h == pytest.approx(6.0)


@pytest.mark.parametrize("house, expected", [
    ("house2", {"heat_pump": ("el", True), "boiler": ("fuel", True), "solar": (None, False)}),
    ("house4", {"boiler": ("fuel", True), "heater": ("el", False)}),
])
def test_kpi_of_other_houses_reports_their_generators(tmp_path, capsys, house, expected):
    """Houses 2 and 4 have no CHP: the generators come from the run's columns, each with the
    energies and counters it records; comfort and DHW (drawn from the main storage) as house 1."""
    csv = tmp_path / "x.csv"
    assert main(["simulate", house, "--days", "1", "--step", "10", "--out-interval", "10",
                 "--out", str(csv), "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["kpi", str(csv)]) == 0
    text = capsys.readouterr().out
    table = text[text.index("  generator"):].splitlines()
    assert [line.split()[0] for line in table[1:]] == list(expected)
    assert "thermal discomfort" in text and "DHW draws" in text and "chp" not in text
    assert main(["kpi", str(csv), "--json"]) == 0
    k = json.loads(capsys.readouterr().out)
    assert k["duration_h"] == pytest.approx(24.0) and k["dhw_draws"] > 10 and k["dhw_failures"] == 0
    assert 90.0 < k["comfort_occupied_pct"] <= 100.0 and k["soc_swings"] is not None
    t, names, rows = load_series(csv)
    last = lambda n: rows[-1, names.index(n)] / 3.6e6  # noqa: E731  J -> kWh of a plant meter
    for g, (energy, counted) in expected.items():
        assert k["generators"][g]["heat_kWh"] > 0.0, g
        if g != "solar":  # solar's pump chatters within a step: its 10 s samples alias (test_python_plc_house2.py)
            assert k[f"heat_{g}_kWh"] == pytest.approx(last(f"{g}.E_heat") if f"{g}.E_heat" in names
                                                       else k[f"el_in_{g}_kWh"], rel=5e-3), g
        if energy == "fuel":
            assert k[f"fuel_{g}_kWh"] == pytest.approx(last(f"{g}.E_fuel"), rel=5e-3)
        if energy == "el":
            assert k[f"el_in_{g}_kWh"] == pytest.approx(-last(f"{g}.E_el"), rel=5e-3) and k[f"el_in_{g}_kWh"] > 1.0
        if counted:
            assert k[f"{g}_starts"] == int(rows[-1, names.index(f"{g}.starts")]) and k[f"{g}_run_h"] > 0
        else:
            assert k[f"{g}_starts"] is None and k[f"{g}_run_h"] is None
    assert k["fuel_kWh"] == pytest.approx(sum(k[f"fuel_{g}_kWh"] or 0.0 for g in expected))
    assert k["el_in_kWh"] == pytest.approx(sum(k[f"el_in_{g}_kWh"] or 0.0 for g in expected))
    assert k["el_out_kWh"] == 0.0 and k["pv_kWh"] > 0.0


def test_kpis_follow_the_columns_a_run_has():
    """A run with a generator only: comfort, DHW and cycling are None, attributes by name work."""
    names = ["heat_pump.Q_flow", "heat_pump.P_el", "mixer.Q_flow"]
    rows = np.tile([6000.0, -2000.0, 5000.0], (3600, 1))
    k = kpis(np.arange(1.0, 3601.0), names, rows)
    assert list(k.generators) == ["heat_pump"]                      # mixer.Q_flow is no generator
    assert k.heat_heat_pump_kWh == pytest.approx(6.0) and k.el_in_heat_pump_kWh == pytest.approx(2.0)
    assert k.heat_pump_starts is None and k.discomfort_Kh is None and k.dhw_draws is None
    assert k.soc_swings is None and k.fuel_kWh == 0.0
    with pytest.raises(AttributeError, match="generators of this run: heat_pump"):
        k.heat_chp_kWh
    with pytest.raises(ConfigError, match="KPIs need a generator"):
        kpis(np.arange(1.0, 11.0), ["mixer.Q_flow"], np.zeros((10, 1)))


def test_dhw_failures_and_soc_swings_are_counted():
    names = ["zone.T_room", "zone.T_set", "dhw.T_tap", "dhw.m_flow_demand", "chp.P_fuel", "boiler.P_fuel",
             "chp.P_el", "chp.Q_flow", "boiler.Q_flow", "chp.starts", "boiler.starts", "chp.run_hours",
             "boiler.run_hours", "storage.SOC"]
    n = 600
    rows = np.zeros((n, len(names)))
    c = {k: i for i, k in enumerate(names)}
    rows[:, c["zone.T_room"]], rows[:, c["zone.T_set"]] = 19.5, 21.0       # 1.5 K below all along
    rows[:, c["dhw.T_tap"]] = 50.0
    rows[100:160, c["dhw.m_flow_demand"]] = 0.1                           # a good draw
    rows[300:420, c["dhw.m_flow_demand"]] = 0.1                           # a draw that goes cold
    rows[360:420, c["dhw.T_tap"]] = 40.0
    # two periods from 0.5: up 0.3, down 0.6, up 0.6, down 0.6, up 0.3 = 5 legs above 0.2
    rows[:, c["storage.SOC"]] = 0.5 + 0.3 * np.sin(np.linspace(0, 4 * np.pi, n))
    k = kpis(8 * 3600 + np.arange(1.0, n + 1), names, rows)              # 08:00, a day hour
    assert k.dhw_draws == 2 and k.dhw_failures == 1 and k.dhw_failure_min == pytest.approx(1.0)
    assert k.discomfort_Kh == pytest.approx(1.5 * n / 3600) and k.comfort_occupied_pct == 0.0
    assert k.occupied_by.startswith("day hours")                          # no presence column
    assert k.soc_swings == 5
    assert soc_swings(0.5 + 0.05 * np.sin(np.arange(1000.0))) == 0        # noise is not cycling


def test_kpi_errors_say_what_to_give(tmp_path):
    with pytest.raises(ConfigError, match="no such recording"):
        load_series(tmp_path / "missing")
    bad = tmp_path / "x.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(ConfigError, match="twin simulate --out"):
        load_series(bad)
