"""The heating circuit of any house found by role, and its emitter replayed alone.

A house's heating circuit is its mixing station, the coupling point it draws from, the emitter it
feeds and the emitter's zone, read from the links (never from instance names): house 1's
`mixer` on `switch` feeding `radiator`, house 2's `mixer` on `heating` feeding `floor`. A
recording that measures the circuit's flow, its supply after mixing and the room lets the emitter
be replayed alone between those measured interfaces, giving its return: a fault of the emitter
(a floor's screed, a radiator's rating) shows there and nowhere else, as the cut has removed the
emitter from the replayed plant.

Each emitter kind is replayed by its own model:
- a radiator as a chain of water elements (EN 442-2 as in Modelica Buildings' RadiatorEN442_2,
  whose default is 5): its return lags its supply by a spread of residence times that one mixed
  node cannot give. The element count, the rating and the water content are calibrated on the
  recorded return: an independent radiator shares neither its discretisation nor its rating
  with the house file. Uncalibrated (too few flowing samples), it is the house file's radiator,
  model and values: the kind's own kernel (OWN).
- a floor by the kind's own kernel (plant/components/floor_heating.step: water and screed as one
  node). Its rating is calibrated on the recorded return; its screed is not, since a screed that
  stores less than the file says is a candidate of its own (effects/units.py SlabCapacity).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import njit

from ..kinds import KINDS
from ..schedule import n_steps
from ..water import CP, RHO

RADIATOR_ELEMENTS = (1, 2, 3, 4, 5, 6, 8)
# emitter kind -> calibrated parameter -> (lo, hi) x the file value. A rating within 0.6-1.4 of
# the file: a datasheet rating at 75/65/20 degC against a house's real sizing; a radiator's water
# content within 0.2-2 (panel types differ by that much per watt)
BOUNDS = {"radiator": {"Q_nominal": (0.6, 1.4), "V_water": (0.2, 2.0)},
          "floor_heating": {"Q_nominal": (0.6, 1.4)}}
ELEMENTS = {"radiator": RADIATOR_ELEMENTS, "floor_heating": (1,)}
# an emitter not calibrated runs its kind's own kernel with the house file's values: the model the
# whole house runs. Before, a radiator kept 5 elements, and the twin's own June recording of house 1
# (14 flowing samples to train on) read +1.01 K on its return: the chain cools faster once the
# pump stops, so it met the room, below which neither emits, 1.3 K lower, and held there for 60 h
OWN = 0


@dataclass(frozen=True)
class Circuit:
    station: str   # the mixing station
    point: str     # the coupling point it draws from
    emitter: str   # the emitter it feeds
    kind: str      # the emitter's kind (a key of BOUNDS)
    zone: str      # the emitter's zone

    @property
    def station_inputs(self) -> tuple:
        """The mixing station alone: recorded set-points and measured interfaces ..."""
        s = self.station
        return (f"{s}.T_sup_set", f"{s}.m_flow_set", f"{self.point}.T_sup", f"{s}.T_ret")

    @property
    def station_outputs(self) -> tuple:
        """... -> its outputs."""
        s = self.station
        return (f"{s}.T_sup", f"{s}.m_flow", f"{s}.y_valve")

    @property
    def emitter_inputs(self) -> tuple:
        """The emitter alone: measured circuit flow, supply after mixing and room -> its return.
        A delayed or lagging return sensor (the circuit return is otherwise a cut boundary,
        compared nowhere) then shows as a mismatch of the return, which a sensor candidate can
        explain."""
        return (f"{self.station}.m_flow", f"{self.station}.T_sup", f"{self.zone}.T_room")

    @property
    def emitter_outputs(self) -> tuple:
        return (f"{self.station}.T_ret",)

    @property
    def bounds(self) -> dict:
        """Override key -> (lo, hi) x the file value of the emitter's calibration."""
        return {f"{self.emitter}.{k}": b for k, b in BOUNDS[self.kind].items()}

    @property
    def elements(self) -> tuple:
        return ELEMENTS[self.kind]

    @property
    def noun(self) -> str:
        return "radiator circuit" if self.kind == "radiator" else "floor heating"


@lru_cache(maxsize=32)
def of(house) -> Circuit | None:
    """The heating circuit of `house`: its one mixing station that one coupling point lists as
    a consumer and whose emitter is of a kind replayed alone (BOUNDS) with a zone; None when the
    house has none or several."""
    from ..declaration import load

    inst = load(house).instances
    found = []
    for st in (i for i in inst.values() if i.kind == "mixing_station"):
        points = [i.name for i in inst.values() if i.kind == "coupling_point"
                  and st.name in (i.options.get("consumers") or ())]
        em = inst.get(st.options.get("emitter"))
        if len(points) == 1 and em is not None and em.kind in BOUNDS and em.options.get("zone"):
            found.append(Circuit(st.name, points[0], em.name, em.kind, em.options["zone"]))
    return found[0] if len(found) == 1 else None


def filled(v: np.ndarray) -> np.ndarray:
    """NaN samples hold the last finite value (the first finite one before it)."""
    v = np.asarray(v, dtype=np.float64)
    ok = np.isfinite(v)
    if ok.all() or not ok.any():
        return np.nan_to_num(v)
    idx = np.where(ok, np.arange(len(v)), np.flatnonzero(ok)[0])
    np.maximum.accumulate(idx, out=idx)
    return v[idx]


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


@njit(cache=True)
def _kernel_run(step, times, m, T_sup, T_room, x, p, out):
    """The emitter kind's own kernel `step` (a floor's water and screed, a radiator's water) over
    the samples, measured interfaces linear between samples; out[i] = its node (the return)."""
    out[0] = x[0]
    for i in range(1, times.shape[0]):
        t0, t1 = times[i - 1], times[i]
        ns = n_steps(t1 - t0)
        h = (t1 - t0) / ns
        for s in range(ns):
            w = (s + 0.5) / ns
            step(h, x, p, m[i - 1] * (1.0 - w) + m[i] * w, T_sup[i - 1] * (1.0 - w) + T_sup[i] * w,
                 T_room[i - 1] * (1.0 - w) + T_room[i] * w)
        out[i] = x[0]


def replay(rec, house: str, overrides: dict, n: int, elements: int = OWN) -> dict:
    """The emitter of `house` (with its overrides) replayed alone over the first n samples from
    the measured circuit flow, supply and room -> {the station's return: values}. A radiator
    runs as `elements` elements in series (OWN: its kind's kernel); every element, or the kernel's
    node, starts at the first recorded return."""
    from ..component import pack
    from ..declaration import params_of

    c = of(house)
    prm = params_of(house, c.emitter, overrides)
    ret = c.emitter_outputs[0]
    T0 = filled(rec.data[ret][:n])[0]
    T0 = T0 if np.isfinite(T0) else prm.T_init
    times = np.ascontiguousarray(rec.time[:n], dtype=np.float64)
    cols = [filled(rec.data[s][:n]) for s in c.emitter_inputs]
    out = np.empty(n)
    if c.kind == "radiator" and elements != OWN:
        k = _element_coefficient(prm.Q_nominal, prm.T_sup_nominal, prm.T_ret_nominal, prm.T_room_nominal,
                                 prm.exponent, elements)
        _radiator_run(times, *cols, np.full(elements, T0), k, prm.exponent, CP * RHO * prm.V_water / elements, out)
    else:
        # the kernel the kind declares its emitter calls (Kind.KERNEL: the module of its step)
        kernel = importlib.import_module(KINDS[c.kind].KERNEL).step
        _kernel_run(kernel, times, *cols, np.array([T0]), pack(prm), out)
    return {ret: out}


def file_values(house: str) -> dict:
    """The house file's values of the emitter's calibrated parameters, by override key."""
    from ..declaration import load

    c = of(house)
    prm = load(house).instances[c.emitter].params
    return {key: float(getattr(prm, key.split(".", 1)[1])) for key in c.bounds}


def _cost(rec, house: str, mask: np.ndarray, elements: int, transform=None):
    """-> (J(values) = MSE of the recorded return on `mask`, the override keys, R(values) = the
    residuals whose sum of squares is J): values in the order of the circuit's bounds, the
    simulated return passed through `transform` when given."""
    c = of(house)
    keys = list(c.bounds)
    ret = c.emitter_outputs[0]
    meas = rec.data[ret]
    n = int(np.flatnonzero(mask).max()) + 1
    m = mask[:n] & np.isfinite(meas[:n])

    def res(values):
        y = replay(rec, house, dict(zip(keys, values)), n, elements)[ret]
        if transform is not None:
            y = transform(y)
        return meas[:n][m] - y[m]

    def J(values):
        return float(np.mean(res(values) ** 2))
    return J, keys, lambda values: res(values) / np.sqrt(max(int(m.sum()), 1))


def fit(rec, house: str, mask: np.ndarray, elements: int, start: dict, transform=None) -> tuple:
    """The emitter's calibrated parameters (elements fixed) that fit the recorded return on
    `mask` (Nelder-Mead within the bounds x the file value), the simulated return passed through
    `transform` when given (a sensor candidate fitted jointly). -> (values, MSE)."""
    from scipy.optimize import minimize

    bounds = of(house).bounds
    file = file_values(house)
    J, keys, _ = _cost(rec, house, mask, elements, transform)
    lo = np.array([bounds[q][0] for q in keys])
    hi = np.array([bounds[q][1] for q in keys])

    def Ju(u):  # relative to the file values; outside the bounds: clipped, plus a penalty
        rel = np.clip(u, lo, hi)
        return J([file[q] * r for q, r in zip(keys, rel)]) + float(np.sum((u - rel) ** 2))

    u0 = np.array([start.get(q, file[q]) / file[q] for q in keys])
    res = minimize(Ju, u0, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-6, "maxfev": 120})
    rel = np.clip(res.x, lo, hi)
    return {q: file[q] * r for q, r in zip(keys, rel)}, float(res.fun)


def calibrate(rec, house: str, mask: np.ndarray) -> dict:
    """The emitter alone calibrated on the recorded return over `mask` (the training window's
    flowing samples): each element count of its kind with its parameters, the best kept. ->
    {elements, values {override: value}, rms_K, per_elements {N: rms}, at_bound, identifiability}."""
    from .calibration import identifiability

    c = of(house)
    file = file_values(house)
    trials = {N: fit(rec, house, mask, N, file) for N in c.elements}
    N = min(trials, key=lambda q: trials[q][1])
    values = trials[N][0]
    at = [q for q, v in values.items() if min(abs(v / file[q] - b) for b in c.bounds[q]) < 2e-3]
    _, keys, R = _cost(rec, house, mask, N)
    t = rec.time[mask]
    ident = identifiability(R, keys, [file[q] * c.bounds[q][0] for q in keys],
                            [file[q] * c.bounds[q][1] for q in keys], [values[q] for q in keys],
                            max(2.0, (t[-1] - t[0]) / 1800.0))
    return {"elements": N, "values": values, "rms_K": float(np.sqrt(trials[N][1])),
            "per_elements": {q: float(np.sqrt(v[1])) for q, v in trials.items()}, "at_bound": at,
            "file_values": file, "identifiability": ident,
            "bounds": {q: [file[q] * b for b in c.bounds[q]] for q in keys}}
