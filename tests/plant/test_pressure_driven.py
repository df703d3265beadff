"""Pressure-driven hydraulics of a coupling point: mass conservation, idle flow, parallel generators."""
import numpy as np
import pytest

from plant.hydraulics import pressure_driven as net

P = net.pack(net.NetworkParams())


def _solve(m_b, m_dem, fixed=False, m_c=0.0):
    sol = np.zeros(net.N_SOL)
    res = net.solve(P, m_b, m_dem, fixed, m_c, 0.0, 0.0, sol)
    return res, sol


@pytest.mark.parametrize("m_b,m_dem,fixed,m_c", [
    (0.0, 0.2, False, 0.0), (0.25, 0.2, False, 0.0), (0.25, 0.0, False, 0.0), (0.0, 0.0, False, 0.0),
    (0.25, 0.5, True, 0.03), (0.0, 0.2, True, 0.03), (0.3, 0.1, True, 0.12), (0.0, 0.533, False, 0.0)])
def test_mass_is_conserved_at_every_node(m_b, m_dem, fixed, m_c):
    res, s = _solve(m_b, m_dem, fixed, m_c)
    assert res < 1e-10
    S = s[net.X_M_STORAGE] + s[net.X_M_CHP] + m_b - m_dem
    assert abs(S) < 1e-10  # R balances by the same flows
    assert s[net.X_M_CHP] >= 0.0  # the flap in the CHP line stops reverse flow


def test_idle_chp_carries_a_share_of_the_heating_flow():
    _, s = _solve(0.0, 0.2)
    share = s[net.X_M_CHP] / 0.2
    assert 0.25 < share < 0.45  # calibrated: about a third of a heating deficit


def test_generators_in_parallel_no_forced_flow_without_a_deficit():
    _, idle = _solve(0.0, 0.0)
    assert abs(idle[net.X_M_CHP]) < 1e-6  # nothing runs: no flow
    _, s = _solve(0.25, 0.1)
    assert s[net.X_PS] > 0.0 and s[net.X_M_CHP] == 0.0  # surplus charges the storage only
    _, d = _solve(0.1, 0.3)
    _, d0 = _solve(0.0, 0.2)
    assert abs(d[net.X_M_CHP] - d0[net.X_M_CHP]) < 1e-9  # only the deficit is shared


def test_pump_speed_follows_the_affinity_law():
    assert net.pump_speed(0.0, 100.0, 4e4, 1e5, 1e5) == 0.0
    n = net.pump_speed(0.2, 0.0, 4e4, 2e5, 1.5e5)
    assert abs(4e4 * n * n - 3.5e5 * 0.04) < 1e-6
