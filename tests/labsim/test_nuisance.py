"""labsim's model-form variations: realisation 0 is the nominal rig, a drawn rig still closes its
ledger, and a generator's thermal mass passes on exactly the heat it does not keep."""
import math

import numpy as np
import pytest

from labsim import nuisance
from labsim.generators import CP, massive_outlet
from labsim.house import LabHouse


def test_realisation_0_is_the_nominal_rig_and_others_are_reproducible_draws():
    assert nuisance.draw(0) == nuisance.NOMINAL
    a, b, c = nuisance.draw(1), nuisance.draw(1), nuisance.draw(2)
    assert a == b and a != c
    for r in (1, 2, 3):
        n = nuisance.draw(r)
        assert all(abs(h - h0) <= 0.03 + 1e-9 for h, h0 in zip(n["storage_sensor_heights"],
                                                                 nuisance.STORAGE_SENSOR_HEIGHTS))
        assert 15.0 <= n["storage_UA"] <= 28.0 and 40e3 <= n["chp_C"] <= 110e3


def test_an_unknown_nuisance_key_is_refused():
    with pytest.raises(ValueError, match="unknown labsim nuisance"):
        LabHouse("2021-01-10", nuisance={"sensor_heigths": ()})


def test_a_drawn_rig_closes_its_ledger():
    h = LabHouse("2021-01-10", {"idle_flow_k": 0.5}, nuisance=nuisance.draw(3))
    for _ in range(4320):  # half a day of 10 s steps
        h.step()
    L = h.closure()
    assert L["fuel"] > 20.0 and h.chp.starts >= 1
    assert abs(L["closure"]) < 1e-9 and abs(L["water_side_closure"]) < 1e-9


def test_a_massive_generator_passes_on_the_heat_it_does_not_keep():
    C, T_in, heat, q, dt = 60e3, 40.0, 5000.0, 0.05, 10.0
    T = T_in
    kept = passed = 0.0
    for _ in range(2000):
        T_new, T_out, Q = massive_outlet(T, C, T_in, heat, q, dt)
        assert Q == pytest.approx(q * CP * (T_out - T_in))
        kept += C * (T_new - T)
        passed += Q * dt
        T = T_new
    assert kept + passed == pytest.approx(2000 * dt * heat, rel=1e-12)
    # settled: the outlet is the steady rise heat / (q c); the approach has time constant C / (q c)
    assert T == pytest.approx(T_in + heat / (q * CP), abs=1e-6)
    T1, _, _ = massive_outlet(T_in, C, T_in, heat, q, C / (q * CP))
    assert (T1 - T_in) / (heat / (q * CP)) == pytest.approx(1.0 - math.exp(-1.0))
    # a standing branch keeps the heat
    T2, T_out2, Q2 = massive_outlet(50.0, C, T_in, 600.0, 0.0, dt)
    assert Q2 == 0.0 and T_out2 == 50.0 and T2 == pytest.approx(50.0 + 600.0 * dt / C)
    assert np.isfinite(T2)
