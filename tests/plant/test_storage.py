"""Stratified storage kernel: losses, energy ledger, front sharpness, buoyancy, coils, params."""
import math

import numpy as np
import pytest

from plant.component import build_params, pack
from plant.components import storage as S
from plant.components import storage_readings as R
from plant.errors import ConfigError
from plant.water import CP, RHO

NO_I = np.zeros(0, dtype=np.int64)
NO_F = np.zeros(0, dtype=np.float64)


def _ports(layers, m, temps=None):
    layers = np.asarray(layers, dtype=np.int64)
    m = np.asarray(m, dtype=np.float64)
    t = np.zeros(len(layers)) if temps is None else np.asarray(temps, dtype=np.float64)
    return layers, m, t


def _run(P, T, n, dt, inflow=None, outflow=None, coil=None):
    """Step n times; returns (sum of Q_loss*dt, sum of Q_coil*dt, last out_T, last coil_Tout)."""
    p = pack(P)
    il, im, iT = inflow if inflow else (NO_I, NO_F, NO_F)
    ol, om, oT = outflow if outflow else (NO_I, NO_F, NO_F.copy())
    if coil:
        ct, cb, cU, cm, cTi = coil
        cTo = np.zeros(len(ct))
    else:
        ct, cb, cU, cm, cTi, cTo = NO_I, NO_I, NO_F, NO_F, NO_F, NO_F.copy()
    q = np.zeros(len(T))
    E_loss = E_coil = 0.0
    for _ in range(n):
        Ql, Qc = S.step(dt, T, p, il, im, iT, ol, om, oT, ct, cb, cU, cm, cTi, cTo, q)
        E_loss += Ql * dt
        E_coil += Qc * dt
    return E_loss, E_coil, oT, cTo


def _front_width(T, T_cold, T_hot):
    """Distance [layers] between the 90 % and the 10 % crossings (T top first, monotone)."""

    def cross(level):
        for k in range(len(T) - 1):
            if (T[k] - level) * (T[k + 1] - level) <= 0.0 and T[k] != T[k + 1]:
                return k + (T[k] - level) / (T[k] - T[k + 1])
        raise AssertionError(f"no crossing of {level}")

    return cross(T_cold + 0.1 * (T_hot - T_cold)) - cross(T_cold + 0.9 * (T_hot - T_cold))


def test_bad_params_raise_config_error_naming_the_key():
    with pytest.raises(ConfigError) as e:
        build_params(S.Params, {"n_layers": 2, "volume": 0.5}, "house1.toml [dhw_tank]")
    assert "n_layers" in str(e.value) and "house1.toml [dhw_tank]" in str(e.value)
    with pytest.raises(ConfigError, match="UA_los"):
        build_params(S.Params, {"UA_los": 7.0}, "house1.toml [dhw_tank]")


def test_initial_state_linear_top_first():
    P = S.Params(n_layers=5, T_init_top=80.0, T_init_bottom=40.0)
    assert np.allclose(S.initial_state(P), [80, 70, 60, 50, 40])


def test_no_flows_only_losses_over_24h_and_stays_stratified():
    P = S.Params()  # 800 l, UA_loss 20 W/K, T_env 18, 80 -> 40 degC, still-water conduction
    T = S.initial_state(P)
    T0 = T.copy()
    dt, n = 60.0, 24 * 60
    p = pack(P)
    q = np.zeros(len(T))
    E0 = R.stored_energy(T, P, 0.0)
    integral = 0.0  # trapezoid of UA_loss (T_mean - T_env) dt, from the states
    E_loss = 0.0
    for _ in range(n):
        before = P.UA_loss * (T.mean() - P.T_env)
        Ql, _ = S.step(dt, T, p, NO_I, NO_F, NO_F, NO_I, NO_F, NO_F.copy(), NO_I, NO_I, NO_F, NO_F, NO_F,
                       NO_F.copy(), q)
        integral += 0.5 * (before + P.UA_loss * (T.mean() - P.T_env)) * dt
        E_loss += Ql * dt
    lost = E0 - R.stored_energy(T, P, 0.0)
    assert lost == pytest.approx(integral, rel=5e-3)
    assert lost == pytest.approx(E_loss, rel=1e-12)
    # analytic mean decay: tau = C_tank / UA = 0.8 * 4.18e6 / 20 = 167,200 s -> 56.7 MJ lost in 24 h
    C_tank = CP * RHO * P.volume
    expected = C_tank * (T0.mean() - P.T_env) * (1.0 - math.exp(-86400.0 * P.UA_loss / C_tank))
    assert lost == pytest.approx(expected, rel=5e-3)
    assert 55e6 < lost < 58e6
    # still stratified: strictly decreasing downward (nothing merged), top-bottom spread nearly kept
    assert np.all(np.diff(T) < 0.0)
    # spread: losses alone keep 40 K * 0.596 = 23.9 K; still-water conduction rounds each end of the
    # linear profile by about G * 2 sqrt(a t / pi) * decay = 24.5 K/m * 0.125 m * 0.6 = 1.8 K
    decay = math.exp(-86400.0 * P.UA_loss / C_tank)
    spread = (T0[0] - T0[-1]) * decay
    assert spread - 2 * 2.2 < T[0] - T[-1] < spread - 2 * 1.2
    # a linear profile is not changed by conduction away from the ends: middle layers just decay
    mid = slice(10, 30)
    assert np.allclose(T[mid] - P.T_env, (T0[mid] - P.T_env) * decay, atol=0.05)


@pytest.mark.parametrize("dt,n", [(1.0, 300), (60.0, 60)])
def test_energy_ledger_exact_with_random_ports_and_coils(dt, n):
    rng = np.random.default_rng(int(dt))
    P = S.Params(n_layers=40)
    p = pack(P)
    T = S.initial_state(P)
    N = len(T)
    q = np.zeros(N)
    C_layer = CP * RHO * P.volume / N
    T_lo, T_hi = 10.0, 90.0
    nsub_seen = set()
    for _ in range(n):
        il = rng.integers(0, N, 2)
        im = rng.uniform(0.0, 0.5, 2)
        iT = rng.uniform(T_lo, T_hi, 2)
        ol = rng.integers(0, N, 2)
        w = rng.uniform(0.1, 1.0, 2)
        om = w / w.sum() * im.sum()
        oT = np.zeros(2)
        ct = np.sort(rng.integers(0, N, 2))
        cb = ct + rng.integers(0, 8, 2)
        cb = np.minimum(cb, N - 1)
        cU = rng.uniform(0.0, 1500.0, 2)
        cm = rng.uniform(0.0, 0.4, 2)
        cm[rng.uniform(size=2) < 0.2] = 0.0
        cTi = rng.uniform(T_lo, T_hi, 2)
        cTo = np.zeros(2)
        nsub_seen.add(S.n_substeps(dt, T, p, il, im, ol, om, cU, cm, ct, cb))
        H0 = C_layer * T.sum()
        Ql, Qc = S.step(dt, T, p, il, im, iT, ol, om, oT, ct, cb, cU, cm, cTi, cTo, q)
        dH = C_layer * T.sum() - H0
        ledger = dt * (CP * np.dot(im, iT) - CP * np.dot(om, oT) - Ql + Qc)
        scale = dt * (CP * np.dot(im, iT) + abs(Qc) + abs(Ql)) + 1.0
        assert abs(dH - ledger) <= 1e-9 * scale, (dH, ledger)
        # the coils give what their fluid loses
        assert Qc == pytest.approx(float(np.sum(cm * CP * (cTi - cTo))), rel=1e-9, abs=1e-6)
        # bounded and stably stratified after every step
        assert T.min() >= T_lo - 1e-9 and T.max() <= T_hi + 1e-9
        assert np.all(np.diff(T) <= 1e-12)
    if dt == 1.0:
        assert nsub_seen == {1}
    else:
        assert max(nsub_seen) > 1  # 60 s at up to 1 kg/s through 20 kg layers needs substeps


def _charge(limiter=None, n_layers=40, seconds=2400, dt=1.0, m=10.0 / 60.0):
    kw = {} if limiter is None else {"limiter": limiter}
    P = S.Params(n_layers=n_layers, UA_loss=0.0, T_init_top=20.0, T_init_bottom=20.0, **kw)
    T = S.initial_state(P)
    _run(P, T, int(seconds / dt), dt, inflow=_ports([0], [m], [70.0]), outflow=_ports([n_layers - 1], [m]))
    return P, T


def test_hot_charge_front_stays_sharp():
    # 800 l tank at 20 degC, 70 degC in at the top at 10 l/min, out at the bottom; after 2400 s the
    # front (400 kg of 800) has travelled half the tank
    P, T = _charge()  # default limiter (superbee)
    assert np.all(np.diff(T) <= 1e-12)  # monotone: top hot, bottom cold
    assert T[0] > 69.9 and T[-1] < 20.01
    # the 50 % crossing sits at half height (front position = 400 kg / 20 kg per layer = layer 20)
    k50 = np.interp(45.0, T[::-1], np.arange(40.0)[::-1])
    assert 19.0 < k50 < 21.5
    dz = P.height / P.n_layers
    w = _front_width(T, 20.0, 70.0)
    _, T_up = _charge(S.LIMITER_UPWIND)
    w_up = _front_width(T_up, 20.0, 70.0)
    _, T_mc = _charge(S.LIMITER_MC)
    w_mc = _front_width(T_mc, 20.0, 70.0)
    # measured: superbee 3.2 layers (0.13 m), MC 4.5 (0.18 m), upwind 11.5 (0.47 m); the inlet
    # layer's own mixing (time constant 120 s) already makes ~2.2 layers
    assert w < 3.6 and w * dz < 0.15
    assert w_mc < 5.0
    assert 10.0 < w_up < 13.0  # upwind: 2.56 * sqrt(2 * u dz/2 * t) = 0.47 m
    assert w <= 0.5 * w_up and w_mc <= 0.5 * w_up


@pytest.mark.parametrize("dt,m", [(60.0, 10.0 / 60.0), (60.0, 20.0 / 60.0), (10.0, 1.0)])
def test_front_bounded_and_sharp_at_large_courant(dt, m):
    # Courant per step 0.5 ... 1.0 (substepped to <= 0.5): still monotone, bounded, sharp
    P, T = _charge(dt=dt, m=m, seconds=400.0 / m)
    assert np.all(np.diff(T) <= 1e-12)
    assert T.max() <= 70.0 + 1e-9 and T.min() >= 20.0 - 1e-9
    assert _front_width(T, 20.0, 70.0) < 3.6


def test_discharge_from_below_front_moves_up_sharp():
    # hot tank, 20 degC return in at the bottom at 10 l/min, hot water out at the top (upward flow)
    P = S.Params(UA_loss=0.0, T_init_top=70.0, T_init_bottom=70.0)
    T = S.initial_state(P)
    m = 10.0 / 60.0
    _, _, oT, _ = _run(P, T, 2400, 1.0, inflow=_ports([39], [m], [20.0]), outflow=_ports([0], [m]))
    assert np.all(np.diff(T) <= 1e-12)
    assert oT[0] > 69.99
    assert 18.5 < np.interp(45.0, T[::-1], np.arange(40.0)[::-1]) < 21.0
    assert _front_width(T, 20.0, 70.0) < 3.6


def test_inversion_is_mixed_energy_unchanged():
    P = S.Params(UA_loss=0.0, UA_layer=0.0)
    T = S.initial_state(P)  # 80 -> 40 degC
    T[30] = 85.0  # hot layer under colder ones
    H0 = T.sum()
    _run(P, T, 1, 1.0)
    assert np.all(np.diff(T) <= 0.0)
    assert T.sum() == pytest.approx(H0, rel=1e-14)
    assert T[30] > S.initial_state(P)[30] + 1.0  # it warmed the layers it rose through
    assert np.all(T[31:] == S.initial_state(P)[31:])  # nothing below it changed


def test_dhw_coil_heats_its_layers_and_energy_is_exact():
    P = S.Params(volume=0.5, height=1.51, UA_loss=7.0, T_init_top=40.0, T_init_bottom=40.0)
    N = P.n_layers
    # charging coil between 50 % and 80 % of the height (original layers 8..6 of 10)
    top, bot = S.port_layer(0.8 * P.height - 1e-9, P), S.port_layer(0.5 * P.height, P)
    assert (top, bot) == (8, 19)
    UA, m, Tin = 0.95 * 675.0, 20.0 / 60.0, 70.0
    coil = (np.array([top]), np.array([bot]), np.array([UA]), np.array([m]), np.array([Tin]))
    T = S.initial_state(P)
    # one step into a uniform tank: outlet follows the exact exchanger formula
    _, E_coil, _, cTo = _run(P, T, 1, 1.0, coil=coil)
    assert cTo[0] == pytest.approx(40.0 + 30.0 * math.exp(-UA / (m * CP)), rel=1e-12)
    T = S.initial_state(P)
    H0 = R.stored_energy(T, P, 0.0)
    E_loss, E_coil, _, cTo = _run(P, T, 600, 1.0, coil=coil)
    assert 40.0 < cTo[0] < Tin
    assert R.stored_energy(T, P, 0.0) - H0 == pytest.approx(E_coil - E_loss, rel=1e-10)
    assert E_coil > 600 * 0.8 * m * CP * (Tin - 40.0) * (1 - math.exp(-UA / (m * CP))) * 0.5
    # the spanned layers (and by buoyancy the ones above) are warmer; below the coil unchanged
    assert np.all(T[top:bot + 1] > 45.0)
    assert np.all(np.abs(T[bot + 3:] - 40.0) < 0.05)
    assert np.all(np.diff(T) <= 1e-12)


def test_substeps_and_outflow_temperature_is_step_mean():
    P = S.Params(n_layers=40, UA_loss=0.0, T_init_top=20.0, T_init_bottom=20.0)
    p = pack(P)
    T = S.initial_state(P)
    m = 1.0  # 60 l/min: 60 s moves 3 layers -> Courant 3 per step
    args = (np.array([0]), np.array([m]), np.array([70.0]), np.array([1]), np.array([m]))
    n = S.n_substeps(60.0, T, p, args[0], args[1], args[3], args[4], NO_F, NO_F, NO_I, NO_I)
    assert n >= 6  # Courant <= 0.5 per substep
    assert S.n_substeps(1.0, T, p, args[0], args[1], args[3], args[4], NO_F, NO_F, NO_I, NO_I) == 1
    oT = np.zeros(1)
    H0 = T.sum()
    S.step(60.0, T, p, args[0], args[1], args[2], args[3], args[4], oT, NO_I, NO_I, NO_F, NO_F, NO_F,
           NO_F.copy(), np.zeros(40))
    # the outflow one layer below the inlet warms during the step: its mean lies strictly between
    assert 20.0 < oT[0] < T[1]
    assert (T.sum() - H0) * RHO * P.volume / 40 == pytest.approx(60.0 * m * (70.0 - oT[0]), rel=1e-12)


def test_helpers_soc_sensors_port_layer():
    P = S.Params()
    T = S.initial_state(P)  # 80 -> 40, mean 60
    assert R.soc(T, *R.SOC_BUFFER) == pytest.approx(0.5)
    assert R.soc(np.full(10, 80.0), *R.SOC_DHW) == pytest.approx(1.0)
    assert R.stored_energy(T, P, 40.0) == pytest.approx(CP * RHO * 0.8 * 20.0)
    # 10 layers -> the 10 sensors are the layers, bottom first
    T10 = np.linspace(80.0, 40.0, 10)
    assert np.allclose(R.sensor_temperatures(T10, 10), T10[::-1])
    # linear profile (layer centres at 0.0125 ... 0.9875 of the height): sensor at z reads
    # 40 + 40 (z - 0.0125) / 0.975, sensors at z = 0.05, 0.15, ... 0.95
    s = R.sensor_temperatures(T, 10)
    z = (np.arange(10) + 0.5) / 10
    assert np.allclose(s, 40.0 + 40.0 * (z - 0.0125) / 0.975, atol=1e-9)
    assert s[0] == pytest.approx(41.538, abs=1e-3)
    assert S.port_layer(0.0, P) == 39 and S.port_layer(P.height, P) == 0
    assert S.port_layer(0.5 * P.height, P) == 19
    with pytest.raises(ConfigError, match="port height"):
        S.port_layer(2.0, P)
    assert S.layer_conductance(P) == pytest.approx(0.6 * (0.8 / 1.63) / (1.63 / 40))



def test_layer_counts_share_one_compiled_plant_and_keep_their_own_states():
    """The state and parameter slots are bounded at run time: a storage of 20, 40 or 80 layers
    runs in one generated plant (one compile per machine, not one per layer count), and so does
    a storage with an inlet plume; each has its own state and closes its energy balance over six
    hours of running."""
    from plant.house import load_house

    houses = {n: load_house("house1", start="2021-01-10", overrides={"storage.n_layers": n, "storage.limiter": 0})
              for n in (20, 40, 80)}
    assert len({h._plant.module.__name__ for h in houses.values()}) == 1
    plumes = {load_house("house1", overrides={"storage.n_layers": n, "switch.storage_inlet_mixing": 0.05})
              ._plant.module.__name__ for n in (20, 40, 80)}
    assert len(plumes) == 1 and plumes.isdisjoint({h._plant.module.__name__ for h in houses.values()})
    for n, h in houses.items():
        assert h.state("storage").shape == (n,)
        for _ in range(6 * 60):
            h.step(60.0)
        L = h.ledger()
        assert L["fuel"] > 0.0 and L["closure"] < 1e-9, (n, L["closure"])
        T = h.state("storage")
        assert np.all(np.isfinite(T)) and np.ptp(T) > 1.0   # still stratified, top to bottom


def test_sensor_heights_share_the_compiled_plant_and_read_where_they_are_placed():
    """A columns file's sensor heights (a diagnosis's override) are a parameter of the step: the
    plant read at them is the house file's compiled plant, and each sensor reads the tank's
    profile at its own height, the equally spaced ones included."""
    from plant.components.storage_kind import _at
    from plant.house import load_house

    z = [0.03, 0.12, 0.2, 0.33, 0.41, 0.5, 0.64, 0.7, 0.86, 0.97]
    plain = load_house("house1", start="2021-01-10")
    placed = load_house("house1", start="2021-01-10", overrides={"storage.sensor_heights": z})
    assert placed._plant.module is plain._plant.module
    for h, heights in ((plain, [(k + 0.5) / 10 for k in range(10)]), (placed, z)):
        for _ in range(120):
            h.step(60.0)
        T = h.state("storage")
        got = [h.get(f"storage.T_sensor_{k}") for k in range(1, 11)]
        assert got == [_at(T, zk) for zk in heights]
        assert len(set(got)) > 5   # a stratified tank: the heights matter


def _worst_layer_by_layer(N, in_layer, in_m, out_layer, out_m):
    """The storage's largest outflow as first written: every layer, its ports summed in order."""
    worst, F_above = 0.0, 0.0
    for k in range(N):
        net, outk = 0.0, 0.0
        for i in range(len(in_layer)):
            if in_layer[i] == k:
                net += in_m[i]
        for j in range(len(out_layer)):
            if out_layer[j] == k:
                net -= out_m[j]
                outk += out_m[j]
        F = F_above + net if k < N - 1 else 0.0
        if F > 0.0:
            outk += F
        if F_above < 0.0:
            outk -= F_above
        if outk > worst:
            worst = outk
        F_above = F
    return worst


def test_the_largest_outflow_visited_port_by_port_is_the_layer_by_layer_one_to_the_bit():
    """worst_outflow skips the layers without a port: 3,000 random tanks (ports on the top and
    bottom layers, several on one layer, idle, NaN and reversed flows) give the same float."""
    from plant.components.storage_flows import worst_outflow

    rng = np.random.default_rng(7)
    for _ in range(3000):
        N = int(rng.integers(1, 90))
        nin, nout = int(rng.integers(0, 6)), int(rng.integers(0, 6))
        layers = lambda n: rng.choice([0, N - 1, *rng.integers(0, N, 4)], n).astype(np.int64)  # noqa: E731
        flows = lambda n: rng.choice([0.0, np.nan, -0.1, *rng.exponential(0.3, 5)], n)  # noqa: E731
        args = (layers(nin), flows(nin), layers(nout), flows(nout))
        got, want = worst_outflow(N, *args), _worst_layer_by_layer(N, *args)
        assert got == want or (np.isnan(got) and np.isnan(want)), (N, args, got, want)
