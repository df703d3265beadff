"""The concealed effects act where they should."""
import numpy as np
import pytest

from rigsim.daq import NAMES
from rigsim.model import Effects, draw_nuisance, simulate

DAYS = 0.3


@pytest.fixture(scope="module")
def base():
    return simulate(draw_nuisance(5), Effects(), days=DAYS, start="2021-01-12")


def _run(**kw):
    return simulate(draw_nuisance(5), Effects(**kw), days=DAYS, start="2021-01-12")


def test_sensor_offset_moves_only_its_channel(base):
    r = _run(sensor_tag="BT_T05", offset_K=-3.0)
    j = NAMES.index("BT_T05")
    assert np.allclose(r.rec[:, j] - base.rec[:, j], -3.0)
    others = [i for i in range(len(NAMES)) if i != j]
    assert np.array_equal(r.rec[:, others], base.rec[:, others])


def test_sensor_delay_shifts_its_channel(base):
    r = _run(sensor_tag="HC_TRL", delay_s=600.0)
    j = NAMES.index("HC_TRL")
    x, y = base.rec[:, j], r.rec[:, j]
    assert np.max(np.abs(y[10:] - x[:-10])) < 0.5   # 10 samples = 600 s (+- time-stamp jitter)
    assert np.max(np.abs(y - x)) > 2.0


def test_sensor_lag_smooths_its_channel(base):
    r = _run(sensor_tag="BT_T10", lag_s=900.0)
    j = NAMES.index("BT_T10")
    assert np.sum(np.abs(np.diff(r.rec[:, j]))) < np.sum(np.abs(np.diff(base.rec[:, j])))


def test_idle_flow_only_through_a_standing_chp():
    # a spring day: the CHP stands for hours
    b = simulate(draw_nuisance(5), Effects(), days=0.5, start="2021-04-20")
    standing = b.aux[:, 1] == 0
    assert standing.mean() > 0.1
    assert np.all(b.aux[standing, 0] == 0.0)
    r = simulate(draw_nuisance(5), Effects(idle_k=0.6), days=0.5, start="2021-04-20")
    st = r.aux[:, 1] == 0
    assert st.any() and r.aux[st, 0].max() > 0.0
    assert r.effect_size["idle_chp_flow_mean_kg_s"] > 0.0
    # while the heating circuit draws and the boiler stands, the deficit flows: more than over all
    # of the standing time, which holds hours without a deficit
    assert r.effect_size["idle_chp_flow_heating_mean_kg_s"] > r.effect_size["idle_chp_flow_mean_kg_s"]
    assert r.closure < 1e-6


def test_valve_leak_shows_during_the_pump_run_on(base):
    # the PLC's run-on drives the valve closed with the pump running: the tight valve's supply
    # falls to the circuit return, a leaking one keeps mixing in header water
    n = NAMES.index
    r = _run(valve_leak=0.2)

    def closed(x):
        flow, tset = x.rec[:, n("HC_FLOW")], x.rec[:, n("HC_TSUP_SET")]
        m = (flow > 0.5) & (tset < 30.0)
        assert m.mean() > 0.02 and np.all(flow[m] < 3.5)   # the run-on's minimum flow, 3 l/min
        return m

    def rise(x):
        m = closed(x)
        return np.median(x.rec[m, n("HC_TVL")] - x.rec[m, n("HC_TRL")])

    assert rise(base) < 1.0 < 4.0 < rise(r)
    assert r.closure < 1e-6
