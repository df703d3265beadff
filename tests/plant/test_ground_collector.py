"""Ground collector: the undisturbed ground profile, the steady state and the transient of the
ground node against their analytic solutions, the brine exchanger, energy balance, bad parameters."""
import math
from dataclasses import replace

import numpy as np
import pytest

from plant.component import build_params, pack
from plant.components import ground_collector as gc
from plant.errors import ConfigError
from plant.water import CP


def test_undisturbed_ground_mean_amplitude_and_phase():
    P = gc.Params()
    p = pack(P)
    taus = np.arange(0.0, gc.YEAR, 3600.0)
    T = np.array([gc.undisturbed(p, tau) for tau in taus])
    xi = P.depth * math.sqrt(math.pi / (P.diffusivity * gc.YEAR))
    assert T.mean() == pytest.approx(P.T_mean + P.gradient * P.depth, abs=1e-9)
    amplitude = (P.T_max_month - P.T_mean) * math.exp(-xi)
    assert (T.max() - T.min()) / 2 == pytest.approx(amplitude, rel=1e-4)
    # the surface peaks at 7/12 of the year; at depth the wave lags by xi/(2 pi) of a year
    assert taus[T.argmax()] / gc.YEAR == pytest.approx(7 / 12 + xi / (2 * math.pi), abs=2e-4)
    assert 5.5 < gc.undisturbed(p, 9 * 86400.0) < 8.0  # 1.5 m deep in mid-January: ~6.9 degC
    flat = pack(replace(P, T_max_month=P.T_mean))
    assert gc.undisturbed(flat, 0.0) == gc.undisturbed(flat, 0.3 * gc.YEAR) == P.T_mean + P.gradient * P.depth


def test_steady_state_matches_the_analytic_solution():
    """Constant extraction Q from a constant undisturbed ground: T_g = T_u - Q/H, and along the
    pipe the brine approaches T_g exponentially (T_g - T_sup = (T_g - T_ret) exp(-UA/(m cp)))."""
    P = replace(gc.Params(), T_max_month=gc.Params().T_mean)
    p, x = pack(P), gc.initial_state(P)
    T_u = gc.undisturbed(p, 0.0)
    Q, dt = 6000.0, 3600.0
    for k in range(int(30 * P.C_ground / P.H_ground / dt)):
        gc.step(dt, x, p, k * dt, Q, 1.0)
    T_g = T_u - Q / P.H_ground
    assert x[gc.X.T_ground] == pytest.approx(T_g, abs=1e-9)
    mc = P.m_flow * CP
    gc.step(dt, x, p, 0.0, Q, 1.0)
    T_sup, T_ret = x[gc.X.T_sup], x[gc.X.T_ret]
    assert T_sup - T_ret == pytest.approx(Q / mc, rel=1e-12)
    assert T_g - T_sup == pytest.approx((T_g - T_ret) * math.exp(-P.UA / mc), rel=1e-9)
    assert T_ret < T_sup < T_g < T_u


def test_ground_node_transient_is_the_first_order_solution():
    P = replace(gc.Params(), T_max_month=gc.Params().T_mean)
    p, x = pack(P), gc.initial_state(P)
    T_u, Q, dt = gc.undisturbed(p, 0.0), 8000.0, 60.0
    tau = P.C_ground / P.H_ground
    n = int(2 * tau / dt)
    for k in range(n):
        gc.step(dt, x, p, k * dt, Q, 1.0)
    exact = T_u - Q / P.H_ground * (1.0 - math.exp(-n * dt / tau))
    assert x[gc.X.T_ground] == pytest.approx(exact, abs=1e-3)


def test_energy_balance_over_a_year_with_intermittent_extraction():
    P = gc.Params()
    p, x = pack(P), gc.initial_state(P, 0.0)
    T0, dt = x[gc.X.T_ground], 600.0
    rng = np.random.default_rng(12)
    for k in range(int(gc.YEAR / dt)):
        on = float(rng.random() < 0.4)
        gc.step(dt, x, p, k * dt, on * rng.uniform(5000.0, 9000.0), on)
        if on < 0.5:
            assert x[gc.X.T_sup] == x[gc.X.T_ret] == x[gc.X.T_ground]  # brine at rest takes the ground's temperature
    stored = P.C_ground * (x[gc.X.T_ground] - T0)
    assert x[gc.X.E_ground] - x[gc.X.E] == pytest.approx(stored, rel=1e-9, abs=1e-6 * x[gc.X.E])
    assert x[gc.X.E] > 0 and x[gc.X.E_ground] > 0  # the undisturbed ground refills the node


def test_initial_state_follows_the_start_time_and_depletion():
    P = replace(gc.Params(), dT_init=2.0)
    x = gc.initial_state(P, 0.5 * gc.YEAR)
    assert x[gc.X.T_ground] == pytest.approx(gc.undisturbed(pack(P), 0.5 * gc.YEAR) - 2.0)
    assert x[gc.X.T_sup] == x[gc.X.T_ret] == x[gc.X.T_ground] and x[gc.X.E] == x[gc.X.E_ground] == 0.0


def test_bad_parameters_are_reported_together():
    with pytest.raises(ConfigError) as exc:
        build_params(gc.Params, {"depth": 0.0, "UA": -1.0, "m_flo": 0.4}, "house.toml [ground]")
    msg = str(exc.value)
    assert "[ground] depth = 0.0: out of range; allowed 0.3 … 200.0 m" in msg
    assert "[ground] UA = -1.0: out of range" in msg
    assert "[ground] m_flo: unknown parameter; did you mean m_flow" in msg
