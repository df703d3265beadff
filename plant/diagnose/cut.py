"""Which part of the house a recording lets the diagnosis replay alone: cuts and subsystems.

A recording that measures the heating circuit's building side (flow, supply after mixing,
return) and the hot water taken is replayed on the house cut at its circuits (derive.py: the
variant follows from the house's links; house 1's is plant/houses/house1_cut_circuit.toml): the
generators, the hydraulic switch, both storages and the DHW coil run on the recorded commands,
while the circuit and the tap are measured boundaries (plant/connections/measured.py). The twin's
own building, room, weather and hot-water profiles then no longer enter the storage's energy
balance, so a load the profiles get wrong cannot drift it (issue 13: 10-12 K storage RMSE on an
independent recording from load differences alone). A recording without them is replayed on the
whole house, as before.

The mixing station, cut out of the plant, is replayed on its own between its measured interfaces
(`circuit`): the twin's kernel (plant/components/mixing_station.step) driven by the recorded
set-points, the measured supply-header temperature (switch.T_sup) and circuit return
(mixer.T_ret), giving the supply after mixing (mixer.T_sup) and the circuit flow: a fault of the
circuit (a leaking valve) shows there and nowhere else. Its parameters are the declaration's
`mixer` instance with the run's overrides (`mixer.leak`), so a candidate sets them the same way
on the whole house and on the cut.

Every comparable signal belongs to one subsystem (roles.py, by kind): the report localises the mismatch
per subsystem.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..components import mixing_station
from ..errors import ConfigError
from ..schedule import n_steps
from ..water import CP, RHO
from .derive import DerivedCut, derive
from .roles import of as roles_of


def circuit_cut(house) -> DerivedCut:
    """The cut a recording that measures the heating circuits and hot-water draws is replayed
    on: `house` cut at its circuits' building side (derive.py)."""
    return derive(house, "circuit")


# the mixing station alone: recorded set-points and measured interfaces -> its outputs
CIRCUIT_INPUTS = ("mixer.T_sup_set", "mixer.m_flow_set", "switch.T_sup", "mixer.T_ret")
CIRCUIT_OUTPUTS = ("mixer.T_sup", "mixer.m_flow", "mixer.y_valve")

# the radiator circuit alone: measured circuit flow, supply after mixing and room -> its return.
# A delayed or lagging return sensor (the circuit return is otherwise a cut boundary, compared
# nowhere) then shows as a mismatch of mixer.T_ret, which a sensor candidate can explain.
RADIATOR_INPUTS = ("mixer.m_flow", "mixer.T_sup", "zone.T_room")
RADIATOR_OUTPUTS = ("mixer.T_ret",)

def select(rec, house: str, required: bool = False):
    """The cut whose recorded signals the recording holds (None: the whole house), and whether
    the mixing station can be replayed alone. required: a recording that allows no cut is an
    error naming what the cut lacks (the whole house would replay on the twin's own building and
    profiles)."""
    try:
        cut = circuit_cut(house)
    except ConfigError as exc:
        if required:
            raise ConfigError(f"{rec.source}: the house cannot be cut: {exc}") from None
        return None, False
    lacks = cut.missing(rec.has)
    if lacks:
        if required:
            raise ConfigError(f"{rec.source}: the columns file maps no boundary a cut can use: cut '{cut.name}' "
                              f"needs {', '.join(cut.bindings.values())} (missing: {', '.join(lacks)}). Map those "
                              f"columns (`twin diagnose --requirements {house}` lists what each enables), or leave "
                              "out --require-cut to replay the whole house on the twin's building and profiles")
        return None, False
    circuit = "mixer" in cut.removes and _alone(house) and all(rec.has(s) for s in CIRCUIT_INPUTS)
    return cut, circuit


def radiator_alone(rec, cut) -> bool:
    """Whether the radiator circuit can be replayed alone (the circuit cut and its inputs recorded)."""
    return cut is not None and "radiator" in cut.removes and all(rec.has(s) for s in RADIATOR_INPUTS + RADIATOR_OUTPUTS)


def cuts_needed(house="house1") -> dict:
    """{what a cut replaces: the recorded signals it needs} for `house`, or why it cannot be cut."""
    key = "heating circuits and hot-water draws (cut 'circuit')"
    try:
        cut = circuit_cut(house)
    except ConfigError as exc:
        return {key: f"not possible: {exc}"}
    return {key: f"all of {', '.join(cut.bindings.values())} (replaces {', '.join(cut.removes)})"}


def _alone(house) -> bool:
    """Whether the mixing station and the radiators can be replayed alone: written for house 1's
    layout (a station `mixer` on the coupling point `switch`, feeding `radiator`)."""
    from ..declaration import load

    inst = load(house).instances
    return (getattr(inst.get("mixer"), "kind", None) == "mixing_station"
            and getattr(inst.get("radiator"), "kind", None) == "radiator"
            and "mixer" in (getattr(inst.get("switch"), "options", {}).get("consumers") or ()))


def requirements(house="house1") -> dict:
    """What each recorded signal enables (twin diagnose --requirements)."""
    out = {}
    try:
        cuts = (circuit_cut(house),)
    except ConfigError:
        cuts = ()
    for cut in cuts:
        for inp, sig in cut.bindings.items():
            out.setdefault(sig, []).append(f"cut '{cut.name}' (binds {inp}; all of "
                                           f"{', '.join(cut.bindings.values())} needed)")
    alone = _alone(house)
    for s in CIRCUIT_INPUTS if alone else ():
        out.setdefault(s, []).append("the mixing station replayed alone (needs the circuit cut and "
                                     f"{', '.join(CIRCUIT_INPUTS)}): compares {', '.join(CIRCUIT_OUTPUTS[:2])}")
    for s in RADIATOR_INPUTS if alone else ():
        out.setdefault(s, []).append("the radiator circuit replayed alone (needs the circuit cut and "
                                     f"{', '.join(RADIATOR_INPUTS)}): compares {', '.join(RADIATOR_OUTPUTS)}")
    out.setdefault("weather.T_air", []).append("checked against the twin's weather profile; drives the "
                                               "room only in the whole-house replay (no cut)")
    for zone in (s.split(".", 1)[0] for cut in cuts for s in cut.removes):
        if f"{zone}.T_room" in roles_of(house).catalogue:
            out.setdefault(f"{zone}.T_room", []).append("compared in the whole-house replay; with the circuit cut "
                                                        "the room is outside the replayed plant")
    return {s: "; ".join(v) for s, v in out.items()}


def _filled(v: np.ndarray) -> np.ndarray:
    """NaN samples hold the last finite value (the first finite one before it)."""
    v = np.asarray(v, dtype=np.float64)
    ok = np.isfinite(v)
    if ok.all() or not ok.any():
        return np.nan_to_num(v)
    idx = np.where(ok, np.arange(len(v)), np.flatnonzero(ok)[0])
    np.maximum.accumulate(idx, out=idx)
    return v[idx]


@njit(cache=True)
def _circuit_run(times, T_set, m_set, T_prim, T_ret, x, p, out):
    """The mixing station over the samples: set-points held (a change from the interval's
    midpoint, as the plant's replay), measured interfaces linear between samples; out[i] =
    (T_sup after mixing, circuit flow, valve share) at sample i."""
    m, mp, T, y = mixing_station.step(0.0, x, p, T_set[0], m_set[0], T_prim[0], T_ret[0])
    out[0, 0], out[0, 1], out[0, 2] = T, m, y
    for i in range(1, times.shape[0]):
        t0, t1 = times[i - 1], times[i]
        n = n_steps(t1 - t0)
        h = (t1 - t0) / n
        for k in range(n):
            w = (k + 0.5) / n
            j = i - 1 if (w < 0.5 and (T_set[i] != T_set[i - 1] or m_set[i] != m_set[i - 1])) else i
            Tp = T_prim[i - 1] * (1.0 - w) + T_prim[i] * w
            Tr = T_ret[i - 1] * (1.0 - w) + T_ret[i] * w
            m, mp, T, y = mixing_station.step(h, x, p, T_set[j], m_set[j], Tp, Tr)
        out[i, 0], out[i, 1], out[i, 2] = T, m, y


def replay_circuit(rec, house: str, overrides: dict, n: int) -> dict:
    """The mixing station of `house` (with the `mixer.*` overrides) replayed alone over the
    first n samples -> {signal: values} for CIRCUIT_OUTPUTS."""
    from ..component import pack
    from ..declaration import load

    spec = load(house, {k: v for k, v in overrides.items() if k.startswith("mixer.")} or None)
    p = pack(spec.instances["mixer"].params)
    x = mixing_station.initial_state(spec.instances["mixer"].params)
    cols = [_filled(rec.data[s][:n]) for s in CIRCUIT_INPUTS]
    out = np.empty((n, 3))
    _circuit_run(np.ascontiguousarray(rec.time[:n], dtype=np.float64), *cols, x, p, out)
    return dict(zip(CIRCUIT_OUTPUTS, out.T))


# The mixing station alone is calibrated too: its valve actuator's running time and its
# controller's integral gain set how the supply after mixing follows a set-point step. The file's
# 120 s actuator and slow integrator reach the new set-point a minute or more late and overshoot;
# labsim's ideal mixer is there within a sample. On its no-effect case the file's values left
# 2.0 K RMS on mixer.T_sup (all of it at set-point steps), calibrated 0.09 K; that residual had
# been the floor under a valve leak's held-out gain.
MIXER_BOUNDS = {"mixer.t_stroke": (1.0, 600.0), "mixer.K_i": (1e-5, 1e-2)}  # s, 1/(K s); log scale


def calibrate_mixer(rec, house: str, mask: np.ndarray) -> dict:
    """The mixing station alone calibrated on the recorded supply after mixing over `mask` (the
    training window's flowing samples): MIXER_BOUNDS on their log scale, a 6 x 6 grid then
    Nelder-Mead from its best point (the two trade off along a valley that a coordinate pass
    crawls). -> {values {override: value}, rms_K, rms_file_K, at_bound, file_values, bounds}."""
    from scipy.optimize import minimize

    from ..declaration import load
    from .bounded import at_bound
    from .effects.base import Param

    prm = load(house).instances["mixer"].params
    keys = list(MIXER_BOUNDS)
    file = {q: float(getattr(prm, q.split(".", 1)[1])) for q in keys}
    meas = rec.data["mixer.T_sup"]
    n = int(np.flatnonzero(mask).max()) + 1
    m = mask[:n] & np.isfinite(meas[:n])
    lo = np.log([MIXER_BOUNDS[q][0] for q in keys])
    hi = np.log([MIXER_BOUNDS[q][1] for q in keys])

    def J(u):  # u: log values; outside the bounds: clipped, plus a penalty
        c = np.clip(u, lo, hi)
        y = replay_circuit(rec, house, dict(zip(keys, np.exp(c))), n)["mixer.T_sup"]
        return float(np.mean((meas[:n][m] - y[m]) ** 2)) + float(np.sum((u - c) ** 2))

    J_file = J(np.log([file[q] for q in keys]))
    grid = [np.array([a, b]) for a in np.linspace(lo[0], hi[0], 6) for b in np.linspace(lo[1], hi[1], 6)]
    u0 = min(grid, key=J)
    res = minimize(J, u0, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-6, "maxfev": 80})
    u = np.clip(res.x, lo, hi)
    values = dict(zip(keys, (float(v) for v in np.exp(u))))
    return {"values": values, "rms_K": float(np.sqrt(J(u))), "rms_file_K": float(np.sqrt(J_file)),
            "at_bound": [q for q in keys if at_bound(Param(q, *MIXER_BOUNDS[q], file[q], "", log=True), values[q])],
            "file_values": file, "bounds": {q: list(b) for q, b in MIXER_BOUNDS.items()}}


# The radiator circuit alone is a chain of water elements (EN 442-2 as in Modelica Buildings'
# RadiatorEN442_2, whose default is 5): its return lags its supply by a spread of residence times
# that one mixed node cannot give. The element count, the rating and the water content are
# calibrated on the recorded return (calibrate_radiator): an independent radiator shares neither
# its discretisation nor its rating with the house file.
RADIATOR_ELEMENTS = (1, 2, 3, 4, 5, 6, 8)
RADIATOR_BOUNDS = {"radiator.Q_nominal": (0.6, 1.4), "radiator.V_water": (0.2, 2.0)}  # x the file value


@njit(cache=True)
def _element_coefficient(Q_N, T_sup_N, T_ret_N, T_room_N, n, N):
    """k of one element's emission k (T - T_room)^n such that the N-element chain gives Q_N at
    the nominal point (supply T_sup_N, return T_ret_N, room T_room_N) in steady state."""
    m = Q_N / (CP * (T_sup_N - T_ret_N))
    lo, hi = 0.0, 100.0 * Q_N / N
    for _ in range(80):
        k = 0.5 * (lo + hi)
        T, Q = T_sup_N, 0.0
        for _e in range(N):
            a, b = T_room_N, T
            for _i in range(60):  # the element's steady outlet: m cp (T_in - x) = k (x - T_room)^n
                x = 0.5 * (a + b)
                if m * CP * (T - x) > k * (x - T_room_N) ** n:
                    a = x
                else:
                    b = x
            Q += m * CP * (T - x)
            T = x
        if Q < Q_N:
            lo = k
        else:
            hi = k
    return 0.5 * (lo + hi)


@njit(cache=True)
def _radiator_run(times, m, T_sup, T_room, x, k, n, C, out):
    """The radiator elements over the samples (each explicit, exactly conservative), measured
    interfaces linear between samples; out[i] = the last element's temperature (the return)."""
    N = x.shape[0]
    out[0] = x[N - 1]
    for i in range(1, times.shape[0]):
        t0, t1 = times[i - 1], times[i]
        ns = n_steps(t1 - t0)
        h = (t1 - t0) / ns
        for s in range(ns):
            w = (s + 0.5) / ns
            mm = m[i - 1] * (1.0 - w) + m[i] * w
            Tr = T_room[i - 1] * (1.0 - w) + T_room[i] * w
            prev = T_sup[i - 1] * (1.0 - w) + T_sup[i] * w
            for e in range(N):
                T = x[e]
                d = T - Tr
                q = k * d ** n if d > 0.0 else 0.0
                x[e] = T + h * (mm * CP * (prev - T) - q) / C
                prev = T
        out[i] = x[N - 1]


def replay_radiator(rec, house: str, overrides: dict, n: int, elements: int = 5) -> dict:
    """The radiator circuit of `house` (with the `radiator.*` overrides) replayed alone over the
    first n samples from the measured circuit flow, supply and room, as `elements` elements in
    series -> {mixer.T_ret: values}. Every element starts at the first recorded return."""
    from ..declaration import load

    prm = load(house, {k: v for k, v in overrides.items() if k.startswith("radiator.")} or None) \
        .instances["radiator"].params
    k = _element_coefficient(prm.Q_nominal, prm.T_sup_nominal, prm.T_ret_nominal, prm.T_room_nominal,
                             prm.exponent, elements)
    T0 = _filled(rec.data["mixer.T_ret"][:n])[0]
    x = np.full(elements, T0 if np.isfinite(T0) else prm.T_init)
    cols = [_filled(rec.data[s][:n]) for s in RADIATOR_INPUTS]
    out = np.empty(n)
    _radiator_run(np.ascontiguousarray(rec.time[:n], dtype=np.float64), *cols, x, k, prm.exponent,
                  CP * RHO * prm.V_water / elements, out)
    return {"mixer.T_ret": out}


def radiator_file_values(house: str) -> dict:
    from ..declaration import load

    prm = load(house).instances["radiator"].params
    return {key: float(getattr(prm, key.split(".", 1)[1])) for key in RADIATOR_BOUNDS}


def _radiator_cost(rec, house: str, mask: np.ndarray, elements: int, transform=None):
    """-> (J(values) = MSE of the recorded return on `mask`, the override keys): values in the
    order of RADIATOR_BOUNDS, the simulated return passed through `transform` when given."""
    keys = list(RADIATOR_BOUNDS)
    meas = rec.data["mixer.T_ret"]
    n = int(np.flatnonzero(mask).max()) + 1
    m = mask[:n] & np.isfinite(meas[:n])

    def J(values):
        y = replay_radiator(rec, house, dict(zip(keys, values)), n, elements)["mixer.T_ret"]
        if transform is not None:
            y = transform(y)
        return float(np.mean((meas[:n][m] - y[m]) ** 2))
    return J, keys


def fit_radiator(rec, house: str, mask: np.ndarray, elements: int, start: dict, transform=None) -> tuple:
    """Rating and water content of the radiator alone (elements fixed) that fit the recorded return
    on `mask` (Nelder-Mead within RADIATOR_BOUNDS x the file value), the simulated return passed
    through `transform` when given (a sensor candidate fitted jointly). -> (values, MSE)."""
    from scipy.optimize import minimize

    file = radiator_file_values(house)
    J, keys = _radiator_cost(rec, house, mask, elements, transform)
    lo = np.array([RADIATOR_BOUNDS[q][0] for q in keys])
    hi = np.array([RADIATOR_BOUNDS[q][1] for q in keys])

    def Ju(u):  # relative to the file values; outside the bounds: clipped, plus a penalty
        rel = np.clip(u, lo, hi)
        return J([file[q] * r for q, r in zip(keys, rel)]) + float(np.sum((u - rel) ** 2))

    u0 = np.array([start[q] / file[q] for q in keys])
    res = minimize(Ju, u0, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-6, "maxfev": 120})
    rel = np.clip(res.x, lo, hi)
    return {q: file[q] * r for q, r in zip(keys, rel)}, float(res.fun)


def calibrate_radiator(rec, house: str, mask: np.ndarray) -> dict:
    """The radiator alone calibrated on the recorded return over `mask` (the training window's
    flowing samples): each element count of RADIATOR_ELEMENTS with its rating and water content,
    the best kept. -> {elements, values {override: value}, rms_K, per_elements {N: rms}, at_bound}."""
    file = radiator_file_values(house)
    trials = {}
    for N in RADIATOR_ELEMENTS:
        trials[N] = fit_radiator(rec, house, mask, N, file)
    N = min(trials, key=lambda q: trials[q][1])
    values = trials[N][0]
    at = [q for q, v in values.items()
          if min(abs(v / file[q] - b) for b in RADIATOR_BOUNDS[q]) < 2e-3]
    from .calibration import identifiability

    J, keys = _radiator_cost(rec, house, mask, N)
    t = rec.time[mask]
    ident = identifiability(J, keys, [file[q] * RADIATOR_BOUNDS[q][0] for q in keys],
                            [file[q] * RADIATOR_BOUNDS[q][1] for q in keys], [values[q] for q in keys],
                            max(2.0, (t[-1] - t[0]) / 1800.0))
    return {"elements": N, "values": values, "rms_K": float(np.sqrt(trials[N][1])),
            "per_elements": {q: float(np.sqrt(v[1])) for q, v in trials.items()}, "at_bound": at,
            "file_values": file, "identifiability": ident,
            "bounds": {q: [file[q] * b for b in RADIATOR_BOUNDS[q]] for q in keys}}
