"""The connection knobs for effects the ideal switch leaves out (fitted by `twin diagnose`):
flow forced through the CHP and inlet mixing in the heating storage keep the energy balance,
do what they say, and are validated like every house-file value."""
import numpy as np
import pytest

from plant.catalogue import CATALOGUE
from plant.errors import ConfigError
from plant.house import load_house
from plant.connections.coupling_point import inlet

DAY = 86400.0


def test_inlet_spreads_the_flow_with_a_fractional_last_layer():
    n = 4  # 1 + ceil(2.5)
    layer, m, T = np.zeros(n, dtype=np.int64), np.zeros(n), np.zeros(n)
    inlet(layer, m, T, 2.5, 40, True, 0, 0.35, 70.0)
    assert list(layer) == [0, 1, 2, 3]
    assert np.allclose(m / m[0], [1.0, 1.0, 1.0, 0.5]) and abs(m.sum() - 0.35) < 1e-15
    assert np.all(T == 70.0)
    inlet(layer, m, T, 2.5, 40, False, 1, 0.35, 40.0)  # upward from the bottom port, clamped
    assert list(layer) == [1, 0, 0, 0] and abs(m.sum() - 0.35) < 1e-15
    one = np.zeros(1, dtype=np.int64), np.zeros(1), np.zeros(1)
    inlet(*one, 0.0, 40, True, 0, 0.123, 60.0)
    assert one[1][0] == 0.123  # no mixing: the whole flow, bit-identical


def test_slots_beyond_the_plume_carry_nothing_and_every_plume_shares_one_compiled_plant():
    exact = np.zeros(4, dtype=np.int64), np.zeros(4), np.zeros(4)
    wide = np.zeros(21, dtype=np.int64), np.zeros(21), np.zeros(21)
    for a in (exact, wide):
        inlet(*a, 2.5, 40, True, 0, 0.35, 70.0)
    assert np.array_equal(wide[1][:4], exact[1]) and np.all(wide[1][4:] == 0.0)
    # a plume of any size runs in the plant compiled for the largest one (no compile per size)
    modules = {load_house("house1", overrides={"switch.storage_inlet_mixing": v})._plant.module.__name__
               for v in (0.03, 0.1, 0.137)}
    assert len(modules) == 1, modules


def test_inlet_mixing_degrades_stratification_and_keeps_the_balance():
    i_top, i_bot = CATALOGUE.index("storage.T_sensor_10"), CATALOGUE.index("storage.T_sensor_1")
    spread = {}
    for v in (0.0, 0.2):
        h = load_house("house1", start="2021-01-10", overrides={"switch.storage_inlet_mixing": v})
        _, rows = h.run(DAY, dt=1.0, out_interval=600.0)
        assert h.ledger()["closure"] < 1e-9
        spread[v] = float(np.mean(rows[:, i_top] - rows[:, i_bot]))
    assert spread[0.2] < spread[0.0] - 1.0, spread  # top-bottom difference shrinks by > 1 K


def test_forced_chp_flow_is_seen_by_the_branch_not_by_the_units_counter():
    h = load_house("house1", start="2021-01-10", overrides={"switch.idle_flow.chp": 0.4})
    _, rows = h.run(DAY, dt=1.0, out_interval=60.0)
    assert h.ledger()["closure"] < 1e-9
    col = {n: CATALOGUE.index(n) for n in ("chp.m_flow", "chp.m_flow_pump", "chp.Q_flow", "chp.Q_flow_meter")}
    assert np.all(rows[:, col["chp.m_flow"]] >= rows[:, col["chp.m_flow_pump"]] - 1e-15)
    idle_flushed = (rows[:, col["chp.m_flow_pump"]] == 0.0) & (rows[:, col["chp.m_flow"]] > 0.0)
    assert idle_flushed.any()
    assert np.all(rows[idle_flushed, col["chp.Q_flow_meter"]] == 0.0)
    heat, meter = rows[:, col["chp.Q_flow"]].sum(), rows[:, col["chp.Q_flow_meter"]].sum()
    assert meter < heat  # the unit's counter misses the heat of the flow its pump did not move


def test_the_idle_share_passes_a_standing_chp_only_and_pump_coupling_a_running_one():
    """A running pump's head sets its branch's flow: the consumers' deficit flushes the CHP only
    while its pump stands; the boiler's suction (pump_coupling) reaches a running one too."""
    col = {n: CATALOGUE.index(n) for n in ("chp.m_flow", "chp.m_flow_pump", "boiler.m_flow")}
    for ov in ({"switch.idle_flow.chp": 0.8}, {"switch.pump_coupling.chp": 0.8}):
        h = load_house("house1", start="2021-01-10", overrides=ov)
        _, rows = h.run(DAY, dt=1.0, out_interval=60.0)
        assert h.ledger()["closure"] < 1e-9
        m, own = rows[:, col["chp.m_flow"]], rows[:, col["chp.m_flow_pump"]]
        running = own > 0.0
        assert running.mean() > 0.1 and (~running).mean() > 0.05
        assert (m[~running] > 0.0).any()  # flushed while standing
        pushed = running & (m > own + 1e-12)
        if "switch.idle_flow.chp" in ov:
            assert not pushed.any()  # the pump's own flow while it runs
        else:
            assert pushed.any() and (rows[pushed, col["boiler.m_flow"]] > 0.0).all()


def test_bad_inlet_mixing_names_the_key_and_the_range():
    with pytest.raises(ConfigError) as e:
        load_house("house1", overrides={"switch.storage_inlet_mixing": 0.6})
    assert "storage_inlet_mixing" in str(e.value) and "half the storage volume" in str(e.value)


def test_a_leaking_port_valve_charges_both_heights_and_keeps_the_balance():
    """House 2's heat pump valve (a branch with { upper, lower } ports): leak = 0 is the closed
    valve; a leak sends its share through the other port pair and the unit draws a mix of both
    returns, so with the valve upper it returns warmer than the valve's own layer alone."""
    rows, names = {}, None
    for leak in (0.0, 0.3):
        h = load_house("house2", start="2021-01-10", overrides={"hp_valve.leak": leak})
        _, rows[leak] = h.run(DAY, dt=10.0, out_interval=600.0)
        assert h.ledger()["closure"] < 1e-9
        names = list(h.catalogue.names)
    j = {n: names.index(n) for n in ("heat_pump.T_ret", "storage.T_sensor_2", "storage.T_sensor_9")}
    assert not np.array_equal(rows[0.0], rows[0.3])
    # the lower port pair takes part of the heat: against the closed valve the tank's top gains
    # less (or loses more) than its bottom
    bottom = rows[0.3][:, j["storage.T_sensor_2"]].mean() - rows[0.0][:, j["storage.T_sensor_2"]].mean()
    top = rows[0.3][:, j["storage.T_sensor_9"]].mean() - rows[0.0][:, j["storage.T_sensor_9"]].mean()
    assert bottom > top, (bottom, top)


def test_bad_port_valve_leak_names_the_key_and_the_range():
    with pytest.raises(ConfigError) as e:
        load_house("house2", overrides={"hp_valve.leak": 0.7})
    assert "hp_valve" in str(e.value) and "leak" in str(e.value) and "0 … 0.5" in str(e.value)
