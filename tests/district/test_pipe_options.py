"""The pipe's options (wall heat capacity, axial dispersion): the energy ledger with each on, the
analytic step response of the wall, the exponential decay at steady state, and the grid with them."""
import math

import numpy as np
import pytest

from district.grid import Draw, Grid, GridSpec, PipeSpec
from plant.grid.pipe import Pipe, taylor_dispersion, wall_capacity
from plant.water import CP

OPTIONS = {"wall": dict(C_wall=1.0e5), "wall_at_b": dict(C_wall=1.0e5, wall_share_b=1.0),
           "dispersion": dict(dispersion=0.05), "both": dict(C_wall=1.0e5, wall_share_b=0.3, dispersion=0.05)}


@pytest.mark.parametrize("name", sorted(OPTIONS))
def test_the_pipe_ledger_closes_with_each_option_on(name):
    """in - out - loss - (change of water and wall heat) = 0 to round-off, flows in both directions."""
    p = Pipe(39.0, 0.05248, 0.46, 18.0, **OPTIONS[name])
    rng = np.random.default_rng(3)
    E0, H_in, H_out = p.energy(), 0.0, 0.0
    for _ in range(2000):
        m = float(rng.normal(0.0, 1.0)) * 3.0
        T_in = float(rng.uniform(10.0, 90.0))
        p.lose(3.0, 18.0)
        M, H = p.push(m, T_in)
        H_in += CP * abs(m) * T_in
        H_out += H
    residual = H_in - H_out - p.E_loss - (p.energy() - E0)
    assert p.E_loss != 0.0
    assert abs(residual) < 1e-11 * H_in


def test_the_default_pipe_is_the_plain_one_bit_for_bit():
    a, b = Pipe(20.0, 0.1, 0.19, 30.0), Pipe(20.0, 0.1, 0.19, 30.0, C_wall=0.0, dispersion=0.0)
    rng = np.random.default_rng(5)
    for _ in range(500):
        m, T = float(rng.normal()) * 20.0, float(rng.uniform(20, 80))
        a.lose(10.0, 10.0), b.lose(10.0, 10.0)
        assert a.push(m, T) == b.push(m, T)
    assert np.array_equal(a.T, b.T) and a.E_loss == b.E_loss


def test_a_step_through_the_wall_at_the_outlet_is_the_first_order_lag_of_c_over_m_cp():
    """No loss, constant flow, the wall lumped at the outlet: after the transport delay the outlet
    approaches the new temperature as 1 - exp(-(t - delay) m cp / C), exactly (the library's model)."""
    C, m_dot, dt = 1.0e5, 0.5, 2.0
    p = Pipe(20.0, 0.1, 0.0, 30.0, C_wall=C, wall_share_b=1.0)
    delay = p.mass / m_dot
    steps = int(round(delay / dt))
    p = Pipe(20.0, 0.1, 0.0, 30.0, C_wall=C, wall_share_b=1.0, merge=0.0)
    p.mass = m_dot * dt * steps                   # a whole number of steps per transport delay
    p.m = np.array([p.mass])
    delay = p.mass / m_dot
    t, out = [], []
    for k in range(1, 600):
        M, H = p.push(m_dot * dt, 70.0)
        t.append(k * dt)
        out.append(p.outlet(+1))
    t, out = np.array(t), np.array(out)
    after = t > delay
    expected = 70.0 - 40.0 * np.exp(-(t[after] - delay) * m_dot * CP / C)
    assert np.max(np.abs(out[after] - expected)) < 1e-9
    assert np.all(out[~after] == 30.0)


def test_steady_loss_with_the_wall_on_is_the_exponential_decay_over_the_pipe():
    U, L, m_dot, T_env = 0.46, 39.0, 0.589, 18.0
    p = Pipe(L, 0.05248, U, 52.0, C_wall=wall_capacity(L, 0.05248, 0.0039, 8000.0, 500.0))
    for _ in range(3000):
        p.lose(1.0, T_env)
        M, H = p.push(m_dot * 1.0, 52.0)
    T_out = T_env + (52.0 - T_env) * math.exp(-U * L / (m_dot * CP))
    # 1e-4 K is 0.04 % of the 0.25 K drop: the 1 s steps quantise the residence time
    assert H / (M * CP) == pytest.approx(T_out, abs=1e-4)


def test_dispersion_smears_a_front_like_the_advection_dispersion_solution():
    """A step at the inlet of a long pipe at constant flow: the outlet follows
    0.5 erfc((L - v t) / (2 sqrt(D t))) (large Peclet number) within the parcels' resolution."""
    D, m_dot, dt = 0.1, 1.0, 1.0
    p = Pipe(100.0, 0.1, 0.0, 0.0, merge=1e-4, dispersion=D)
    v = m_dot / (p.mass / 100.0)
    t, out = [], []
    for k in range(1, 1400):
        p.lose(dt, 0.0)
        M, H = p.push(m_dot * dt, 1.0)
        t.append(k * dt)
        out.append(H / (M * CP))
    t, out = np.array(t), np.array(out)
    from scipy.special import erfc
    exact = 0.5 * erfc((100.0 - v * t) / (2.0 * np.sqrt(D * t)))
    assert np.max(np.abs(out - exact)) < 0.05
    assert 0.3 < float(np.interp(100.0 / v, t, out)) < 0.7
    assert 1e-4 < taylor_dispersion(0.05248, 0.589) < 1.0


def test_the_grid_with_wall_and_dispersion_closes_its_ledger():
    pipes = (PipeSpec("pa", "plant", "a", wall_capacity=2e5, dispersion=0.05),
             PipeSpec("ab", "a", "b", wall_capacity=2e5, wall_share_b=1.0), PipeSpec("ac", "a", "c", dispersion=0.1))
    g = Grid(GridSpec("plant", ("plant", "a", "b", "c"), pipes, attach={"h_b": "b", "h_c": "c"},
                      T_init_supply=65.0, T_init_return=35.0))
    rng = np.random.default_rng(2)
    for _ in range(300):
        pub = {h: g.temperatures(h) for h in g.houses}
        draws = {}
        for h in g.houses:
            M = float(rng.uniform(0.0, 0.4)) * 60.0
            if rng.uniform() < 0.6:
                draws[h] = Draw(M_extracted=M, H_extracted_back=M * CP * (pub[h][0] - 25.0))
            else:
                draws[h] = Draw(M_fed_in=M, H_fed_in_back=M * CP * 80.0)
        g.step(60.0, draws, pub)
    L = g.ledger()
    assert L["pipe_losses"] > 0 and L["closure"] < 1e-12
