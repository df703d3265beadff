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
set-points, the measured temperature of the coupling point it draws from (house 1's switch.T_sup)
and the circuit return, giving the supply after mixing and the circuit flow: a fault of the
circuit (a leaking valve) shows there and nowhere else. Its parameters are the declaration's
station with the run's overrides (house 1's `mixer.leak`), so a candidate sets them the same way
on the whole house and on the cut. The station, its coupling point and its emitter are found by
role (emitter.of); the emitter is replayed alone too (emitter.py).

Every comparable signal belongs to one subsystem (roles.py, by kind): the report localises the mismatch
per subsystem.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..components import mixing_station
from ..errors import ConfigError
from ..schedule import n_steps
from .derive import DerivedCut, derive
from .emitter import filled, of as circuit_of
from .roles import of as roles_of


def circuit_cut(house, generators=()) -> DerivedCut:
    """The cut a recording that measures the heating circuits and hot-water draws is replayed
    on: `house` cut at its circuits' building side (derive.py), and at the measured outlets of
    `generators`."""
    return derive(house, "circuit", generators)


def select(rec, house: str, required: bool = False, generators=()):
    """The cut whose recorded signals the recording holds (None: the whole house), and whether
    the mixing station can be replayed alone. required: a recording that allows no cut is an
    error naming what the cut lacks (the whole house would replay on the twin's own building and
    profiles). generators: run those at their measured outlets too (outlet_cuttable)."""
    try:
        cut = circuit_cut(house, generators)
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
    c = circuit_of(house)
    circuit = c is not None and c.station in cut.removes and all(rec.has(s) for s in c.station_inputs)
    return cut, circuit


def outlet_cuttable(rec, house, unit: str) -> bool:
    """Whether the recording measures a generator's outlet temperature and flow and its kind can
    run at them (derive.OUTLET_KINDS: the boiler), so that a cut can (derive.OUTLET)."""
    from ..declaration import load
    from .derive import OUTLET, OUTLET_KINDS

    inst = load(house).instances.get(unit)
    return (inst is not None and inst.kind in OUTLET_KINDS
            and all(rec.has(f"{unit}.{recorded}") for _, recorded in OUTLET))


def emitter_alone(rec, cut, house) -> bool:
    """Whether the emitter can be replayed alone (the circuit cut, its inputs and its return
    recorded: emitter.py)."""
    c = circuit_of(house)
    return (cut is not None and c is not None and c.emitter in cut.removes
            and all(rec.has(s) for s in c.emitter_inputs + c.emitter_outputs))


def cuts_needed(house="house1") -> dict:
    """{what a cut replaces: the recorded signals it needs} for `house`, or why it cannot be cut."""
    key = "heating circuits and hot-water draws (cut 'circuit')"
    try:
        cut = circuit_cut(house)
    except ConfigError as exc:
        return {key: f"not possible: {exc}"}
    return {key: f"all of {', '.join(cut.bindings.values())} (replaces {', '.join(cut.removes)})"}


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
    c = circuit_of(house) if cuts else None
    for s in c.station_inputs if c else ():
        out.setdefault(s, []).append("the mixing station replayed alone (needs the circuit cut and "
                                     f"{', '.join(c.station_inputs)}): compares {', '.join(c.station_outputs[:2])}")
    for s in c.emitter_inputs if c else ():
        out.setdefault(s, []).append(f"the {c.noun} replayed alone (needs the circuit cut and "
                                     f"{', '.join(c.emitter_inputs)}): compares {', '.join(c.emitter_outputs)}")
    out.setdefault("weather.T_air", []).append("checked against the twin's weather profile; drives the "
                                               "room only in the whole-house replay (no cut)")
    for zone in (s.split(".", 1)[0] for cut in cuts for s in cut.removes):
        if f"{zone}.T_room" in roles_of(house).catalogue:
            out.setdefault(f"{zone}.T_room", []).append("compared in the whole-house replay; with the circuit cut "
                                                        "the room is outside the replayed plant")
    return {s: "; ".join(v) for s, v in out.items()}


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
    """The mixing station of `house` (with its overrides) replayed alone over the first n
    samples -> {signal: values} for its circuit's station_outputs (emitter.Circuit)."""
    from ..component import pack
    from ..declaration import load

    c = circuit_of(house)
    spec = load(house, {k: v for k, v in overrides.items() if k.startswith(f"{c.station}.")} or None)
    p = pack(spec.instances[c.station].params)
    x = mixing_station.initial_state(spec.instances[c.station].params)
    cols = [filled(rec.data[s][:n]) for s in c.station_inputs]
    out = np.empty((n, 3))
    _circuit_run(np.ascontiguousarray(rec.time[:n], dtype=np.float64), *cols, x, p, out)
    return dict(zip(c.station_outputs, out.T))


# The mixing station alone is calibrated too: its valve actuator's running time and its
# controller's integral gain set how the supply after mixing follows a set-point step. The file's
# 120 s actuator and slow integrator reach the new set-point a minute or more late and overshoot;
# labsim's ideal mixer is there within a sample. On its no-effect case the file's values left
# 2.0 K RMS on mixer.T_sup (all of it at set-point steps), calibrated 0.09 K; that residual had
# been the floor under a valve leak's held-out gain.
STATION_BOUNDS = {"t_stroke": (1.0, 600.0), "K_i": (1e-5, 1e-2)}  # s, 1/(K s); log scale


def calibrate_mixer(rec, house: str, mask: np.ndarray, overrides: dict | None = None) -> dict:
    """The mixing station alone calibrated on the recorded supply after mixing over `mask` (the
    training window's flowing samples): STATION_BOUNDS on their log scale, a 6 x 6 grid then
    Nelder-Mead from its best point (the two trade off along a valley that a coordinate pass
    crawls); `overrides` (a candidate's) held. -> {values {override: value}, rms_K, rms_file_K,
    at_bound, file_values, bounds}."""
    from scipy.optimize import minimize

    from ..declaration import load
    from .bounded import at_bound
    from .effects.base import Param

    c = circuit_of(house)
    prm = load(house).instances[c.station].params
    bounds = {f"{c.station}.{k}": b for k, b in STATION_BOUNDS.items()}
    keys = list(bounds)
    file = {q: float(getattr(prm, q.split(".", 1)[1])) for q in keys}
    sup = c.station_outputs[0]
    meas = rec.data[sup]
    n = int(np.flatnonzero(mask).max()) + 1
    m = mask[:n] & np.isfinite(meas[:n])
    lo = np.log([bounds[q][0] for q in keys])
    hi = np.log([bounds[q][1] for q in keys])

    def J(u):  # u: log values; outside the bounds: clipped, plus a penalty
        v = np.clip(u, lo, hi)
        y = replay_circuit(rec, house, {**(overrides or {}), **dict(zip(keys, np.exp(v)))}, n)[sup]
        return float(np.mean((meas[:n][m] - y[m]) ** 2)) + float(np.sum((u - v) ** 2))

    J_file = J(np.log([file[q] for q in keys]))
    grid = [np.array([a, b]) for a in np.linspace(lo[0], hi[0], 6) for b in np.linspace(lo[1], hi[1], 6)]
    u0 = min(grid, key=J)
    res = minimize(J, u0, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-6, "maxfev": 80})
    u = np.clip(res.x, lo, hi)
    if J(u) > J_file:  # the grid's cells can all miss the file's point (rigsim house 2: 0.657 -> 0.665 K)
        u = np.log([file[q] for q in keys])
    values = dict(zip(keys, (float(v) for v in np.exp(u))))
    return {"values": values, "rms_K": float(np.sqrt(J(u))), "rms_file_K": float(np.sqrt(J_file)),
            "at_bound": [q for q in keys if at_bound(Param(q, *bounds[q], file[q], "", log=True), values[q])],
            "file_values": file, "bounds": {q: list(b) for q, b in bounds.items()}}
