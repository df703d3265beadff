"""House 1 as a whole: energy ledger, controller thresholds, determinism, remote inputs, house files."""
import numpy as np
import pytest

from plant.components.generator import Mode
from plant.errors import ConfigError, SignalError
from plant.declaration import HOUSES
from plant.house import load_house


def test_seven_day_energy_balance_closes_within_0_1_percent_of_fuel(house1):
    house1.run(7 * 86400, dt=1.0, out_interval=3600)
    L = house1.ledger()
    assert L["fuel"] > 1000 * 3.6e6  # a January week burns over 1 MWh
    assert L["closure"] < 1e-3
    assert L["closure"] < 1e-9  # in fact exact to round-off: every enthalpy flow is counted once
    # each term is physical: heat went to the building, to hot water and to losses
    assert L["heat_building"] > 0 and L["heat_dhw"] > 0 and L["losses"] > 0
    assert L["generator_losses"] > 0
    assert 0.05 < L["el_net"] / L["fuel"] < 0.25


def test_balance_closes_at_ten_second_steps():
    house = load_house("house1")
    house.run(2 * 86400, dt=10.0, out_interval=600)
    assert house.ledger()["closure"] < 1e-9


def test_rule_based_controller_switches_at_its_thresholds():
    house = load_house("house1", start="2021-01-20")
    names = house.catalogue.names
    t, rows = house.run(2 * 86400, dt=2.0, out_interval=2.0)
    col = {n: rows[:, names.index(n)] for n in ("chp.on", "boiler.U_set", "dhw_pump.on",
                                                 "storage.T_sensor_10", "storage.T_sensor_1",
                                                 "dhw_storage.T_sensor_10")}
    top, bottom, dhw_top = col["storage.T_sensor_10"], col["storage.T_sensor_1"], col["dhw_storage.T_sensor_10"]
    # the controller of step k sees the sensors written at the end of step k-1 (row k-1)
    events = 0
    for name, on_ok, off_ok in (
        ("chp.on", lambda i: top[i] < 65.0, lambda i: bottom[i] > 70.0),
        ("boiler.U_set", lambda i: top[i] < 60.0, lambda i: bottom[i] > 70.0),
        ("dhw_pump.on", lambda i: dhw_top[i] < 50.0 and dhw_top[i] < top[i],
         lambda i: dhw_top[i] > 65.0 or top[i] < dhw_top[i]),
    ):
        u = col[name] > 0.5
        rises = np.flatnonzero(~u[:-1] & u[1:]) + 1
        falls = np.flatnonzero(u[:-1] & ~u[1:]) + 1
        assert len(rises) >= 2 and len(falls) >= 2, f"{name} did not cycle in two winter days"
        for i in rises:
            assert on_ok(i - 1), f"{name} switched on at t={t[i]} without its on-condition"
        for i in falls:
            assert off_ok(i - 1), f"{name} switched off at t={t[i]} without its off-condition"
        events += len(rises) + len(falls)
    assert events > 10


def test_same_inputs_same_results_and_snapshot_restore(house1):
    house1.run(3600, dt=1.0)
    snap = house1.snapshot()
    house1.set("boiler.U_set", 10.0)
    house1.run(1800, dt=1.0)
    a = house1.values()
    house1.restore(snap)
    house1.set("boiler.U_set", 10.0)
    house1.run(1800, dt=1.0)
    np.testing.assert_array_equal(a, house1.values())
    fresh = load_house("house1")
    fresh.run(3600, dt=1.0)
    fresh.set("boiler.U_set", 10.0)
    fresh.run(1800, dt=1.0)
    np.testing.assert_array_equal(a, fresh.values())


def test_remote_input_overrides_built_in_control_until_released():
    house = load_house("house1", controller="external")
    house.step(600)
    assert house.get("boiler.U_set") == 0.0 and house.get("chp.on") == 0.0  # nothing drives them
    house.set("boiler.U_set", 10.0)
    T0 = house.get("storage.T_top")
    for _ in range(60):
        house.step(60)
    assert house.get("boiler.mode") == Mode.STEADY and house.get("boiler.Q_flow") > 5000
    assert house.get("boiler.U_set") == 10.0
    house.release("boiler.U_set")  # the rule-based controller takes over again
    house.step(5)
    assert house.get("boiler.U_set") in (0.0, 10.0)
    assert not house.is_remote("boiler.U_set")
    assert house.get("storage.T_top") > T0 - 5.0
    with pytest.raises(SignalError, match="only inputs"):
        house.set("storage.T_top", 50.0)
    with pytest.raises(SignalError, match="did you mean"):
        house.get("storage.T_tpo")


def test_type_day_block_drives_the_house_with_its_own_weather(tmp_path):
    src = (HOUSES / "house1.toml").read_text()
    path = tmp_path / "td.toml"
    path.write_text(src.replace("[profiles]\n", "[profiles]\ntypeday = 11\n"))
    cold = load_house(path)  # block 11: the cold spell, daily means about -8 degC
    cold.run(3 * 86400, dt=10.0, out_interval=3600)
    names = cold.catalogue.names
    t, rows = load_house(path).run(3 * 86400, dt=10.0, out_interval=3600)
    assert rows[:, names.index("weather.T_air")].mean() < -5.0
    assert cold.ledger()["closure"] < 1e-9
    path.write_text(src.replace("[profiles]\n", "[profiles]\ntypeday = 12\n"))
    with pytest.raises(ConfigError, match=r"typeday = 12: must be 0 .* 1 … 11"):
        load_house(path)
