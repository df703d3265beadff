"""Heat pumps CHA-10 (air) and BWS-1-10 (brine): table points, start delay, defrost, aux heater, limits."""
import numpy as np
import pytest

from plant.component import index_of, pack
from plant.components import heat_pump as hp
from plant.tables import interp2
from plant.water import CP

TA = hp.tables_air()
TB = hp.tables_brine()


def test_indices_match_field_order():
    for name, i in index_of(hp.ParamsAir).items():
        assert getattr(hp, "A_" + name.upper() if name != "T_defrost" else "A_T_DEFROST_AMB") == i, name
    for name, i in index_of(hp.ParamsBrine).items():
        assert getattr(hp, "B_" + name.upper()) == i, name


def run_air(n, y=1.0, aux=0.0, T_amb=2.0, T_in=30.0, on=1.0, x=None, t0=0.0, dt=1.0, record=False):
    p = pack(hp.ParamsAir())
    x = hp.initial_state(None) if x is None else x
    t, out, r = t0, [], None
    for _ in range(n):
        r = hp.step_air(t, dt, x, p, *TA, on, y, aux, T_amb, 0.0, T_in)
        if record:
            out.append((t,) + r)
        t += dt
    return x, (np.array(out) if record else r)


@pytest.mark.parametrize(
    "T_amb, y, kW, cop",
    [(-7.0, 0.2, 3.2, 5.4), (-7.0, 1.0, 7.5, 3.9), (2.0, 0.2, 4.0, 6.4), (2.0, 1.0, 9.4, 4.65),
     (7.0, 1.0, 11.6, 5.4)],
)
def test_air_worked_numbers_w35(T_amb, y, kW, cop):
    x, r = run_air(200, y=y, T_amb=T_amb, T_in=30.0)
    m, T_out, P_el, P_heat, mode = r
    assert mode == 3.0
    assert P_heat / 1000 == pytest.approx(kW, rel=0.01)
    assert P_heat / -P_el == pytest.approx(cop, rel=0.01)
    assert T_out == pytest.approx(35.0, abs=1e-9) and m == pytest.approx(P_heat / (CP * 5.0))
    Tk, Ta = 308.15, T_amb + 273.15
    el_amb, q_amb, el_mod, q_mod = TA
    assert P_heat == pytest.approx(interp2(Tk, Ta, q_amb) * interp2(Tk, y, q_mod) * 5750.0, rel=1e-12)
    assert -P_el == pytest.approx(interp2(Tk, Ta, el_amb) * interp2(Tk, y, el_mod) * 5750.0 / 4.65, rel=1e-12)


def test_air_w55_lower_cop():
    _, r = run_air(200, y=0.2, T_amb=-7.0, T_in=50.0)
    assert r[3] / 1000 == pytest.approx(2.1, rel=0.03) and r[3] / -r[2] == pytest.approx(2.0, rel=0.05)
    _, r = run_air(200, y=1.0, T_amb=7.0, T_in=50.0)
    assert r[3] / 1000 == pytest.approx(9.1, rel=0.02) and r[3] / -r[2] == pytest.approx(2.5, rel=0.03)


def test_air_start_delay_and_aux_heater():
    x, rec = run_air(100, y=0.2, aux=0.5, T_amb=2.0, record=True)
    assert np.all(rec[:10, 5] == 1.0) and np.all(rec[:10, 4] == 0.0) and np.all(rec[:10, 1] == 0.0)
    row = rec[-1]
    assert row[5] == 3.0
    # aux stage 2 = 4 kW; the compressor request is forced to 1 (slew from 1 at start)
    _, base = run_air(100, y=1.0, aux=0.0, T_amb=2.0)
    assert row[4] == pytest.approx(base[3] + 4000.0, rel=1e-12)
    assert row[3] == pytest.approx(base[2] - 4000.0, rel=1e-12)
    assert row[4] == pytest.approx(row[1] * CP * (row[2] - 30.0), rel=1e-12)


def test_air_defrost_below_5_degC():
    x, rec = run_air(3700, y=1.0, T_amb=0.0, record=True)
    d = rec[:, 5] == 7.0
    assert d.sum() == 120  # 60 s in each 1800 s of run time
    assert np.all(rec[d, 4] == 0.0) and np.all(rec[d, 3] == 0.0) and np.all(rec[d, 1] == 0.0)
    assert rec[1740, 5] == 7.0 and rec[1739, 5] == 3.0 and rec[1800, 5] == 3.0
    # the defrost completes even when the on-signal drops
    x, _ = run_air(1745, y=1.0, T_amb=0.0)
    x, rec = run_air(80, on=0.0, T_amb=0.0, x=x, t0=1745.0, record=True)
    assert np.all(rec[:55, 5] == 7.0) and np.all(rec[55:, 5] == 0.0) and rec[-1, 3] == -15.0
    # no defrost at 7 degC
    x, rec = run_air(3700, y=1.0, T_amb=7.0, record=True)
    assert not np.any(rec[:, 5] == 7.0)


def test_air_return_limit():
    _, r = run_air(50, T_in=68.5)
    assert r[4] == 5.0 and r[3] == 0.0 and r[2] == -15.0


def run_brine(n, T_src=0.0, T_in=30.0, on=1.0, aux=0.0, record=False):
    p = pack(hp.ParamsBrine())
    x = hp.initial_state(None)
    t, out, r = 0.0, [], None
    for _ in range(n):
        r = hp.step_brine(t, 1.0, x, p, *TB, on, aux, T_src, 0.0, T_in)
        if record:
            out.append((t,) + r)
        t += 1.0
    return x, (np.array(out) if record else r)


@pytest.mark.parametrize(
    "T_src, T_in, kW, cop", [(0.0, 30.0, 10.3, 4.44), (0.0, 50.0, 9.6, 2.7), (10.0, 30.0, 13.5, 6.0)]
)
def test_brine_worked_numbers(T_src, T_in, kW, cop):
    x, r = run_brine(400, T_src=T_src, T_in=T_in)
    m, T_out, P_el, P_heat, mode = r
    assert mode == 3.0
    assert P_heat / 1000 == pytest.approx(kW, rel=0.01)
    assert P_heat / -P_el == pytest.approx(cop, rel=0.01)
    assert T_out == pytest.approx(T_in + 5.0)
    # heat from the source = P_heat + P_el (compressor heat minus compressor power)
    assert x[hp.X_ESRC] == pytest.approx(100 * (P_heat + P_el), rel=1e-12)


def test_brine_start_delay_and_limits():
    x, rec = run_brine(400, record=True)
    assert np.all(rec[:300, 5] == 1.0) and np.all(rec[:300, 4] == 0.0) and rec[300, 5] == 3.0
    _, r = run_brine(400, T_src=-6.0)
    assert r[4] == 5.0 and r[3] == 0.0 and r[2] == -15.0
    _, r = run_brine(400, on=0.0, aux=1.0)  # an aux request alone starts the unit
    _, base = run_brine(400)
    assert r[3] == pytest.approx(base[3] + 6000.0) and r[4] == 3.0
