"""Condensing boiler Wolf CGB-14: steady tables, 0-10 V mapping, start-up, run-on, lock-out, anti-cycling."""
import numpy as np
import pytest

from plant.component import pack
from plant.components import boiler
from plant.components.generator import Mode
from plant.tables import interp2
from plant.water import CP

TABS = boiler.tables()
TP, TDT, TEFF, START, COOL = TABS


def make(**kw):
    P = boiler.Params(**kw)
    return P, pack(P), boiler.initial_state(P)


def run(x, p, t0, n, dt=1.0, U=10.0, m_ext=0.0, T_in=40.0, record=False):
    t, out, r = t0, [], None
    for _ in range(n):
        r = boiler.step(t, dt, x, p, *TABS, U, m_ext, T_in)
        if record:
            out.append((t,) + r)
        t += dt
    return t, (np.array(out) if record else r)


def steady(T, m):
    Tk = T + 273.15
    P = interp2(Tk, m, TP) * 14000.0
    return P, interp2(Tk, m, TDT) * 20.0, interp2(Tk, m, TEFF) * 1.05


@pytest.mark.parametrize(
    "T_in, U, kW, spread, eta, l_min",
    [(40.0, 2.0001, 6.1, 14.9, 1.007, 5.9), (40.0, 6.0, 12.8, 19.4, 1.020, 9.4),
     (40.0, 10.0, 17.4, 19.1, 1.022, 13.1), (60.0, 10.0, 18.1, 17.5, 0.985, 14.8)],
)
def test_steady_state_worked_numbers(T_in, U, kW, spread, eta, l_min):
    P, p, x = make()
    _, r = run(x, p, 0.0, 400, T_in=T_in, U=U)
    m, T_out, P_el, P_fuel, P_heat, mode = r
    assert mode == Mode.STEADY and P_el == 0.0
    assert P_heat / 1000 == pytest.approx(kW, rel=0.01)
    assert T_out - T_in == pytest.approx(spread, rel=0.01)
    assert P_heat / P_fuel == pytest.approx(eta, rel=0.01)
    assert m * 60 == pytest.approx(l_min, rel=0.01)
    P_ss, dT, e = steady(T_in, min(1.0, U / 10))
    assert P_heat == pytest.approx(P_ss, rel=1e-9) and T_out - T_in == pytest.approx(dT, rel=1e-9)


def test_analogue_input_mapping():
    P, p, x = make()
    _, r = run(x, p, 0.0, 50, U=2.0)
    assert r[5] == 0.0 and r[3] == 0.0 and r[2] == -35.0 and r[0] == 0.0
    _, r = run(x, p, 50.0, 400, U=5.0, T_in=50.0)
    assert r[4] == pytest.approx(steady(50.0, 0.5)[0], rel=1e-9)
    P, p, x = make()
    _, r = run(x, p, 0.0, 400, U=12.0, T_in=50.0)
    assert r[4] == pytest.approx(steady(50.0, 1.0)[0], rel=1e-9)
    P, p, x = make()
    _, r = run(x, p, 0.0, 400, U=3.0, T_in=50.0)
    assert r[4] == pytest.approx(steady(50.0, 0.3)[0], rel=1e-9)


@pytest.mark.parametrize("use_flow", [False, True])
def test_start_up_follows_table(use_flow):
    P, p, x = make(use_flow_column=use_flow)
    _, rec = run(x, p, 0.0, 320, U=2.5, T_in=45.0, record=True)  # request 0.25 reached after 10 s
    P_ss, dT, eta = steady(45.0, 0.25)
    q_ss = P_ss / (CP * dT)
    for tau in (20, 50, 100, 170, 250, 299):
        row = rec[tau]
        assert row[6] == 1.0
        f = np.interp(tau, START[:, 0], START[:, 1])
        fq = np.interp(tau, START[:, 0], START[:, 2]) if use_flow else f
        assert row[5] == pytest.approx(f * P_ss, rel=1e-9)
        assert row[4] == pytest.approx(P_ss / eta, rel=1e-9)
        assert row[1] == pytest.approx(fq * q_ss, rel=1e-9)
    assert rec[300, 6] == 3.0 and rec[300, 5] == pytest.approx(P_ss, rel=1e-9)
    # overshoot of the measured start-up (1.26 at about 170 s)
    assert rec[170, 5] / P_ss == pytest.approx(1.26, rel=0.01)


def test_run_on_after_stop():
    P, p, x = make()
    t, r = run(x, p, 0.0, 400, U=10.0, T_in=40.0)
    m_stop = r[0]
    t_off = t
    for k in range(80):
        m, T_out, P_el, P_fuel, P_heat, mode = boiler.step(t, 1.0, x, p, *TABS, 0.0, 0.0, 40.0)
        tau = t - t_off
        if tau < 70:
            assert mode == Mode.RUN_ON and P_fuel == 0.0 and P_el == -35.0
            assert m == pytest.approx(np.interp(tau, COOL[:, 0], COOL[:, 2]) * m_stop, rel=1e-9)
            mod = max(0.2, x[boiler.X.y])
            expected = np.interp(tau, COOL[:, 0], COOL[:, 1]) * steady(40.0, mod)[0]
            assert P_heat == pytest.approx(min(expected, m * CP * 30.0), rel=1e-9, abs=1e-9)
            if tau in (1, 10, 40):
                assert P_heat == pytest.approx(expected, rel=1e-9)
        else:
            assert mode == Mode.IDLE and m == 0.0 and P_heat == 0.0
        t += 1.0


def test_lock_out_hysteresis():
    P, p, x = make(t_anti_cycle=0.0)
    t, r = run(x, p, 0.0, 400, T_in=60.0)
    t, rec = run(x, p, t, 100, T_in=75.5, record=True)
    assert rec[0, 6] == 4.0 and np.all(rec[:, 4] == 0.0) and rec[-1, 6] == 5.0
    t, r = run(x, p, t, 50, T_in=72.0)  # between release and lock-out: still locked
    assert r[5] == 5.0 and x[boiler.X.starts] == 1
    t, r = run(x, p, t, 5, T_in=69.0)
    assert r[5] == 1.0 and x[boiler.X.starts] == 2


def test_anti_short_cycle():
    P, p, x = make()
    t, _ = run(x, p, 0.0, 400)
    t, rec = run(x, p, t, 100, U=0.0, record=True)  # stop
    t_off = rec[0, 0]
    t, rec = run(x, p, t, 250, U=10.0, record=True)  # request again 100 s after the stop
    waiting = rec[rec[:, 0] - t_off < 300]
    assert np.all(waiting[:, 6] == 6.0) and np.all(waiting[:, 4] == 0.0)
    started = rec[rec[:, 0] - t_off >= 300]
    assert started[0, 6] == 1.0 and x[boiler.X.starts] == 2


@pytest.mark.parametrize("dt", [1.0, 10.0])
def test_heat_equals_enthalpy_flux(dt):
    P, p, x = make()
    t, E = 0.0, 0.0
    for k in range(int(4 * 3600 / dt)):
        U = 10.0 * (0.5 + 0.5 * np.sin(t / 700.0)) if (t % 3600) < 2500 else 0.0
        m_ext = 0.5 if 3000 < (t % 3600) < 3300 else 0.0
        T_in = 40.0 + 30.0 * (t / 14400.0)
        m, T_out, P_el, P_fuel, P_heat, mode = boiler.step(t, dt, x, p, *TABS, U, m_ext, T_in)
        assert P_heat == pytest.approx(m * CP * (T_out - T_in), rel=1e-12, abs=1e-9)
        if mode == Mode.STEADY:
            assert P_fuel - P_heat - P_el > -0.06 * P_fuel  # eta <= 1.05 on LHV basis
        E += P_heat * dt
        t += dt
    assert x[boiler.X.E_heat] == pytest.approx(E, rel=1e-12)
    assert x[boiler.X.starts] >= 4
