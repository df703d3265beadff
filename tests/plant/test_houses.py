"""The five CoSES houses: each compiles and closes its energy ledger, their built-in rules switch
at their thresholds, the laboratory names resolve, and bad house files are rejected in full."""
import numpy as np
import pytest

from cli.main import main as twin
from plant.errors import ConfigError
from plant.house import load_house
from plant.housefile import ALIASES, resolve


@pytest.mark.parametrize("name", ["house2", "house3", "house4", "house5"])
def test_house_runs_a_january_week_with_its_ledger_closed(name):
    house = load_house(name, start="2021-01-10")
    house.run(2 * 86400, dt=10.0, out_interval=3600)
    assert house.ledger()["closure"] < 1e-9
    house.run(5 * 86400, dt=10.0, out_interval=3600)
    L = house.ledger()
    assert L["closure"] < 1e-3  # the 7-day figure (0.1 %) ...
    assert L["closure"] < 1e-9  # ... in fact closed to round-off
    assert L["fuel"] > 0 and L["heat_building"] > 0 and L["heat_dhw"] > 0 and L["losses"] > 0
    assert 19.0 < house.get("zone.T_room") < 23.0


def _edges(u):
    u = u > 0.5
    return np.flatnonzero(~u[:-1] & u[1:]) + 1, np.flatnonzero(u[:-1] & ~u[1:]) + 1


def _check(name, u, on_ok, off_ok):
    rises, falls = _edges(u)
    assert len(rises) >= 1 and len(falls) >= 1, f"{name} did not switch in two winter days"
    for i in rises:
        assert on_ok(i), f"{name} switched on at row {i} without its on-condition"
    for i in falls:
        assert off_ok(i), f"{name} switched off at row {i} without its off-condition"
    return len(rises) + len(falls)


def test_heat_pump_rules_switch_at_their_thresholds():
    house = load_house("house2", start="2021-03-25")  # two days in which every actuator cycles (with the
    # TABULA-class building the January storage stays above the valve's 55 degC all day)
    names = house.catalogue.names
    _, rows = house.run(2 * 86400, dt=5.0, out_interval=5.0)  # 5 s: the longest internal step
    col = lambda n: rows[:, names.index(n)]  # noqa: E731
    T = {k: col(f"storage.T_sensor_{k}") for k in (2, 3, 5, 7, 8, 10)}
    valve, hp, aux, boiler = (col(f"controller.{k}") > 0.5 for k in ("valve_upper", "hp_on", "aux_on", "boiler_on"))
    # the rules of step i see the sensors written at the end of step i-1 (row i-1) and the new
    # states of the actuators evaluated before them in the same scan (row i)
    events = _check("valve", valve, lambda i: T[8][i - 1] < 55.0, lambda i: T[7][i - 1] > 60.0)
    events += _check("heat pump", hp, lambda i: valve[i] or T[3][i - 1] < 43.0,
                     lambda i: not valve[i] and T[2][i - 1] > 45.0)
    events += _check("back-up heater", aux, lambda i: hp[i] and (T[8][i - 1] < 50.0 or T[3][i - 1] < 35.0),
                     lambda i: not hp[i] or ((T[7][i - 1] > 55.0 or not valve[i]) and T[2][i - 1] > 40.0))
    events += _check("boiler", boiler, lambda i: T[10][i - 1] < 55.0 or T[5][i - 1] < 35.0,
                     lambda i: T[5][i - 1] > 60.0)
    assert events > 10
    # the commands reach the actuators they are linked to
    np.testing.assert_array_equal(col("hp_valve.upper"), col("controller.valve_upper"))
    np.testing.assert_array_equal(col("heat_pump.on"), col("controller.hp_on"))
    np.testing.assert_array_equal(col("heat_pump.aux"), col("controller.aux_on"))
    np.testing.assert_array_equal(col("boiler.U_set"), 10.0 * col("controller.boiler_on"))


def test_soc_rules_switch_at_their_thresholds():
    house = load_house("house5", start="2021-01-20")
    names = house.catalogue.names
    _, rows = house.run(2 * 86400, dt=5.0, out_interval=5.0)  # 5 s: the longest internal step
    col = lambda n: rows[:, names.index(n)]  # noqa: E731
    soc, T8, T3 = col("storage.SOC"), col("storage.T_sensor_8"), col("storage.T_sensor_3")
    events = 0
    for key, soc_on, on_below, soc_off in (("chp_on", 0.60, 65.0, 0.95), ("boiler_on", 0.50, 60.0, 0.65)):
        events += _check(key, col(f"controller.{key}"),
                         lambda i: soc[i - 1] < soc_on and T8[i - 1] < on_below,
                         lambda i: soc[i - 1] > soc_off or T3[i - 1] > 70.0)
    assert events > 4
    np.testing.assert_array_equal(col("chp.on"), col("controller.chp_on"))


def test_laboratory_names_resolve_to_the_house_files():
    for alias, name in ALIASES.items():
        assert resolve(alias) == resolve(name)
        assert resolve(alias.lower()) == resolve(name)
    with pytest.raises(ConfigError, match="SF1, SF2"):
        resolve("SF6")


def test_twin_houses_list_prints_one_line_per_house(capsys):
    assert twin(["houses", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 5
    for line, (alias, name) in zip(lines, ALIASES.items()):
        assert line.split()[:2] == [name, alias]
        assert "generators:" in line and "storage:" in line and "emitters:" in line
    assert "heat_pump_brine" in lines[2] and "floor_heating" in lines[2]


def test_bad_heights_and_missing_links_are_all_reported(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[house]\nname = "bad"\nbase = "house2"\n\n'
                   '[hp_valve]\nsupply = { upper = 2.5, lower = 0.56 }\n\n'
                   '[controller]\ninputs = { T_valve_on = "storage.T_sensor_8", T_valve_off = "storage.T_sensor_7", '
                   'T_hp_on = "storage.T_sensor_3", T_boiler_top = "storage.T_sensor_10", '
                   'T_boiler = "storage.T_sensor_5" }\n')
    with pytest.raises(ConfigError) as exc:
        load_house(bad)
    message = str(exc.value)
    assert "supply.upper = 2.5: outside the storage 'storage'; allowed 0 … 1.6 m" in message
    assert "inputs.T_hp_off: missing" in message


def test_house4_heats_its_hot_water_through_the_fresh_water_coil():
    """SF4's DHW: cold water rises through the 4.8 kW/K coil and is mixed down to 45 degC; the heat
    taken by the tap water is what the storage gives the coil (the ledger closes)."""
    house = load_house("house4", start="2021-01-12")
    names = house.catalogue.names
    _, rows = house.run(86400, dt=5.0, out_interval=5.0)
    col = lambda n: rows[:, names.index(n)]  # noqa: E731
    drawing = col("dhw.m_flow_demand") > 0
    assert drawing.sum() > 50
    assert np.all(col("dhw.m_flow_hot")[drawing] <= col("dhw.m_flow_demand")[drawing] + 1e-12)
    need = col("dhw.m_flow_demand") * 4180.0 * (45.0 - 15.0)
    ok = drawing & (col("dhw.Q_flow_missing") < 0.02 * need)  # the valve lags the coil by one step
    assert ok.mean() > 0.8 * drawing.mean()  # the coil serves most draws in full
    assert np.mean(np.abs(col("dhw.T_tap")[ok] - 45.0) < 1.0) > 0.95  # mixed down to the set-point
    assert house.ledger()["closure"] < 1e-9 and house.ledger()["heat_dhw"] > 5 * 3.6e6
