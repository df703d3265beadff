"""The truth plant: idle CHP cools, parallel generators, ledger, ideal mode = twin."""
import numpy as np
import pytest

from plant.components.generator import Mode
from plant.house import load_house
from plant.truth import load_truth


@pytest.fixture(scope="module")
def truth():
    return load_truth("house1", start="2021-01-10", controller="external")


def _drive(h, chp_on, boiler_u, m_heat=0.25):
    for name, v in (("chp.on", chp_on), ("chp.y_set", 1.0), ("boiler.U_set", boiler_u),
                    ("dhw_pump.on", 0.0), ("mixer.T_sup_set", 60.0), ("mixer.m_flow_set", m_heat)):
        h.set(name, v)


def test_idle_chp_sees_flow_and_its_outlet_cools(truth):
    truth.reset()
    _drive(truth, 1.0, 0.0)
    truth.run(3600.0, dt=1.0, out_interval=3600.0)
    T_hot = truth.get("chp.T_sup")
    assert T_hot > 55.0  # below 80 degC: part of the heating deficit is forced through the CHP
    _drive(truth, 0.0, 0.0)
    truth.run(1800.0, dt=1.0, out_interval=1800.0)
    m = truth.get("chp.m_flow")
    assert truth.get("chp.mode") == Mode.IDLE and truth.get("chp.m_flow_pump") == 0.0
    assert 0.02 < m < 0.15
    assert 0.15 < m / truth.get("mixer.m_flow_primary") < 0.4
    assert truth.get("chp.T_sup") < T_hot - 15.0
    assert abs(truth.get("chp.T_sup") - truth.get("chp.T_ret")) < 2.0  # flushed to the return


def test_running_boiler_does_not_force_flow_through_the_running_chp(truth):
    # generators in parallel on the headers (the twin's layout): with a surplus the CHP runs on
    # its own pump and reaches its set outlet, as in the twin
    truth.reset()
    _drive(truth, 1.0, 10.0, m_heat=0.2)
    truth.run(3600.0, dt=1.0, out_interval=3600.0)
    assert truth.get("boiler.m_flow") > 0.1 and truth.get("chp.mode") == Mode.STEADY
    assert truth.get("switch.p_supply") > 0.0 and truth.get("switch.m_flow_forced") == 0.0
    assert truth.get("chp.m_flow") == truth.get("chp.m_flow_pump") > 0.0
    assert truth.get("chp.T_sup") > 79.0
    assert truth.get("boiler.T_ret") == truth.get("chp.T_ret")  # both draw from the return header


def test_ledger_closes_and_network_converges():
    h = load_truth("house1", start="2021-01-10")
    h.run(2 * 86400.0, dt=1.0, out_interval=3600.0)
    L = h.ledger()
    assert L["fuel"] > 0 and L["closure"] < 1e-6
    assert h.get("switch.residual") < 1e-9


def test_ideal_mode_reproduces_the_twin():
    tw = load_house("house1", start="2021-01-10")
    tr = load_truth("house1", start="2021-01-10", network={"enabled": False}, storage_layers=40,
                    inlet_mixing_layers=1)
    _, a = tw.run(6 * 3600.0, dt=1.0, out_interval=600.0)
    _, b = tr.run(6 * 3600.0, dt=1.0, out_interval=600.0)
    b = b[:, [tr.catalogue.index(n) for n in tw.catalogue.names]]  # the truth has more signals
    # the truth's substation is feed-in only (its pressure-driven switch takes two generators):
    # idle, its house-side readings show the supply header where the twin's show the return's
    same = [j for j, n in enumerate(tw.catalogue.names) if n not in ("substation.T_sup", "substation.T_ret")]
    assert len(same) == len(tw.catalogue.names) - 2
    assert np.allclose(a[:, same], b[:, same], rtol=1e-9, atol=1e-6)


def test_sensor_lag_and_inlet_mixing_options():
    h = load_truth("house1", start="2021-01-10", network={"enabled": False}, storage_layers=40,
                   inlet_mixing_layers=8, sensor_lag={10: 600.0})
    h.run(6 * 3600.0, dt=1.0, out_interval=3600.0)
    assert h.ledger()["closure"] < 1e-6
    from plant.components.storage_readings import sensor_temperatures

    raw = sensor_temperatures(h.state("storage"))
    assert abs(h.get("storage.T_sensor_9") - raw[8]) < 1e-9  # not lagged
    assert 0.0 < abs(h.get("storage.T_sensor_10") - raw[9]) < 10.0  # lagged
