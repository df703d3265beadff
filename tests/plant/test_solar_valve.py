"""House 3's solar valve (reference §12.4, §8.4): the collector's flow goes to the upper coil
(layers 9..7 of 10) or to the lower one (5..1); the rules switch it at their thresholds, an
external controller can take it over, the heat goes into the layers of the coil in use, the
ledger closes, and a coil outside the tank is rejected with its file and line."""
import numpy as np
import pytest

from plant.components import solar_collector as sc
from plant.errors import ConfigError
from plant.house import load_house
from plant.water import CP, RHO


@pytest.fixture(scope="module")
def summer_morning():
    """House 3 from 21 June 06:00 to 12:00 at 1 s, every step recorded."""
    house = load_house("house3", start="2021-06-21")
    house.run(6 * 3600, dt=10.0, out_interval=3600.0)
    _, rows = house.run(6 * 3600, dt=1.0, out_interval=1.0)
    return house, list(house.catalogue.names), rows


def test_valve_switches_at_its_thresholds(summer_morning):
    _, names, rows = summer_morning
    col = lambda n: rows[:, names.index(n)]  # noqa: E731
    upper = col("solar.upper") > 0.5
    dT = col("solar.T_collector") - col("storage.T_sensor_9")
    # the rules of step i see the signals written at the end of step i-1 (row i-1)
    want = np.where(dT[:-1] > 3.0, True, np.where(dT[:-1] < 2.0, False, upper[:-1]))
    np.testing.assert_array_equal(upper[1:], want)
    rises = np.flatnonzero(~upper[:-1] & upper[1:])
    assert len(rises) >= 1 and upper.any() and not upper.all()
    np.testing.assert_array_equal(col("solar.upper"), col("controller.solar_upper"))
    pumping = col("solar.m_flow") > 0.0
    assert (pumping & upper).any() and (pumping & ~upper).any()
    Qu = col("solar.Q_flow_upper")
    np.testing.assert_array_equal(Qu, np.where(upper, col("solar.Q_flow"), 0.0))


def test_an_external_controller_takes_the_valve_over(summer_morning):
    house, _, _ = summer_morning
    snap = house.snapshot()
    try:
        names = list(house.catalogue.names)
        house.set("solar.upper", 0.0)
        _, rows = house.run(600, dt=1.0, out_interval=1.0)
        col = lambda n: rows[:, names.index(n)]  # noqa: E731
        assert (col("solar.upper") == 0.0).all() and (col("solar.Q_flow_upper") == 0.0).all()
        assert (col("controller.solar_upper") == 1.0).any()  # the rules would have gone upper
        house.release("solar.upper")
        house.step(1.0)
        assert house.get("solar.upper") == house.get("controller.solar_upper")
    finally:
        house.release("solar.upper")
        house.restore(snap)


def test_heat_goes_into_the_layers_of_the_coil_in_use(summer_morning):
    """One step from the same stratified storage (70 degC top to 20 degC bottom), a 90 degC
    collector and the pump at full flow, with the valve up and down: the difference of the
    layers' heat is the upper coil's heat in layers 9..7 and minus the lower coil's in 5..1."""
    house, _, _ = summer_morning
    st = house.decl.instances["storage"].params
    C_layer = RHO * CP * st.volume / st.n_layers
    snap = house.snapshot()
    result = {}
    try:
        for side in (1.0, 0.0):
            house.restore(snap)
            house.set_state("storage", np.linspace(70.0, 20.0, st.n_layers))
            collector = house.state("solar").copy()
            collector[sc.X.T] = collector[sc.X.T_ret] = 90.0
            house.set_state("solar", collector)
            for name, value in (("solar.on", 1.0), ("solar.m_flow_set", 0.333), ("solar.upper", side)):
                house.set(name, value)
            house.step(1.0)
            result[side] = (house.state("storage").copy(), house.get("solar.Q_flow"), house.get("solar.Q_flow_upper"))
    finally:
        for name in ("solar.on", "solar.m_flow_set", "solar.upper"):
            house.release(name)
        house.restore(snap)
    (x_up, Q_up, Qu_up), (x_lo, Q_lo, Qu_lo) = result[1.0], result[0.0]
    assert Q_up > 1000.0 and Q_lo > 1000.0 and Qu_up == Q_up and Qu_lo == 0.0
    d = C_layer * (x_up - x_lo)  # J per layer, index 0 = top
    layer = lambda height: st.n_layers - 1 - min(int(height / st.height * st.n_layers), st.n_layers - 1)  # noqa: E731
    upper = slice(layer(1.564), layer(1.196) + 1)  # original layers 9..7
    lower = slice(layer(0.828), layer(0.092) + 1)  # original layers 5..1
    assert (d[upper] > 0.0).all() and (d[lower] < 0.0).all()
    assert d[upper].sum() == pytest.approx(Q_up * 1.0, rel=1e-2)
    assert d[lower].sum() == pytest.approx(-Q_lo * 1.0, rel=1e-2)
    outside = np.ones(st.n_layers, bool)
    outside[upper] = outside[lower] = False
    assert np.abs(d[outside]).sum() < 1e-2 * (Q_up + Q_lo)


def test_a_leaking_valve_heats_through_both_coils(tmp_path):
    """The valve set to the upper coil with a quarter of the flow through the lower one (leak =
    0.25): both coils' layers take heat from a 90 degC collector, the upper coil gives less than
    the whole, the storage takes what the loop gives, and the ledger closes over a summer day."""
    leaky = tmp_path / "leaky.toml"
    leaky.write_text('[house]\nname = "leaky"\nbase = "house3"\n\n[solar]\nleak = 0.25\n')
    house = load_house(leaky, start="2021-07-20")
    st = house.decl.instances["storage"].params
    C_layer = RHO * CP * st.volume / st.n_layers
    house.run(12 * 3600, dt=10.0, out_interval=3600.0)
    house.set_state("storage", np.linspace(70.0, 20.0, st.n_layers))
    collector = house.state("solar").copy()
    collector[sc.X.T] = collector[sc.X.T_ret] = 90.0
    house.set_state("solar", collector)
    for name, value in (("solar.on", 1.0), ("solar.m_flow_set", 0.333), ("solar.upper", 1.0)):
        house.set(name, value)
    x0 = house.state("storage").copy()
    house.step(1.0)
    d = C_layer * (house.state("storage") - x0)
    Q, Q_up = house.get("solar.Q_flow"), house.get("solar.Q_flow_upper")
    layer = lambda height: st.n_layers - 1 - min(int(height / st.height * st.n_layers), st.n_layers - 1)  # noqa: E731
    upper = slice(layer(1.564), layer(1.196) + 1)
    lower = slice(layer(0.828), layer(0.092) + 1)
    assert d[upper].sum() > 0.0 and d[lower].sum() > 0.0
    assert 0.0 < Q_up < Q
    assert d[lower].sum() == pytest.approx(Q - Q_up, rel=2e-2)
    day = load_house(leaky, start="2021-07-20")
    day.run(86400, dt=10.0, out_interval=3600.0)
    # the leak through the upper coil while the valve is lower cools the top of the tank: the
    # upper coil's heat may end below zero, the loop's is positive
    assert day.ledger()["closure"] < 1e-9 and day.get("solar.E_heat_upper") < day.get("solar.E_heat") > 0.0


def test_ledger_closes_over_two_summer_days():
    house = load_house("house3", start="2021-07-20")
    _, rows = house.run(2 * 86400, dt=10.0, out_interval=3600.0)
    L = house.ledger()
    assert L["closure"] < 1e-9
    E, E_up = house.get("solar.E_heat"), house.get("solar.E_heat_upper")
    assert 0.0 < E_up < E
    assert L["heat_solar"] > E > 0.0


@pytest.mark.parametrize("solar, message", [
    ("top = { upper = 2.5, lower = 0.828 }", "top.upper = 2.5: outside the storage 'storage'; allowed 0 … 1.84 m"),
    ("top = { upper = 0.7, lower = 0.828 }", "top.upper = 0.7: the upper coil's inlet must be above the lower coil's"),
    ("UA_upper = 0.0", "UA_upper = 0.0: two coils need the upper coil's conductance"),
])
def test_a_bad_second_coil_is_rejected_with_file_and_line(tmp_path, solar, message):
    bad = tmp_path / "bad.toml"
    bad.write_text('[house]\nname = "bad"\nbase = "house3"\n\n[solar]\n' + solar + "\n")
    with pytest.raises(ConfigError) as exc:
        load_house(bad)
    assert f"{bad}:6 [solar] {message}" in str(exc.value)


def test_one_coil_with_an_upper_conductance_is_rejected(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[house]\nname = "bad"\nbase = "house3"\n\n[solar]\ntop = 0.828\nbottom = 0.092\n'
                   'UA_upper = 1282.5\n\n[controller]\noutputs = { valve_upper = "hp_branch.upper", '
                   'hp_on = "heat_pump.on", aux = "heat_pump.aux" }\n')
    with pytest.raises(ConfigError) as exc:
        load_house(bad)
    assert f"{bad}:8 [solar] UA_upper = 1282.5: only with two coils" in str(exc.value)


def test_a_leak_without_a_second_coil_is_rejected(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[house]\nname = "bad"\nbase = "house2"\n\n[solar]\nleak = 0.2\n')
    with pytest.raises(ConfigError) as exc:
        load_house(bad)
    assert f"{bad}:6 [solar] leak = 0.2: only a solar valve between two coils leaks" in str(exc.value)
