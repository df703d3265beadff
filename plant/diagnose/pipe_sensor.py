"""A temperature sensor on a pipe that stands or barely flows: modelled, so it can carry evidence.

A sensor in a pipe reads its fluid while the fluid flows. When the branch stands, the water at the
sensor cools toward the plant room (Newton cooling of the stagnant pipe water), which the twin's
generator (it holds its outlet at the last running value) does not model. Between the two, a
trickle renews the water at the sensor only in part: the replay's reading follows the branch's
*simulated* flow m through the pipe water M upstream of the sensor (plug flow): in a sample
interval dt the share r = min(1, m dt / M) of the water at the sensor is fresh fluid, the rest has
cooled toward the plant-room temperature with time constant tau:

    T_k = r fluid_k + (1 - r) (T_room + (T_{k-1} - T_room) exp(-dt / tau))

A running branch (m dt >= M) reads its fluid exactly and a standing one (m = 0) the exponential from
its last flowing value, as a switch between the two would; a trickle reads in between, continuously
in m.

Why a model and not a mask: which branch flows is itself what some missing physics changes. An
idle CHP that a header short-circuit keeps flowing reads the return water in the lab, while a
stagnant twin CHP reads a cooled pipe: masked, that difference (the clearest sign of the idle
flow) was invisible; modelled, the candidate that makes the twin's CHP branch flow removes it.
Why continuous in m: an idle flow of a few tenths of a g/s (labsim's pair_idle_flow_lag at night)
kept the lab's sensors on the return header's water for hours, while a switch at 1 g/s left the
twin's sensors cooling (8-9 K held-out on both CHP sensors); a switch at any other flow is as
arbitrary, and would make a candidate's cost jump where its flow crosses it.

tau (a pipe's insulation, diameter and the sensor's well) and M (where the sensor sits on its
pipe), on no data sheet, are calibrated per branch on the training window only, at the samples
where the replay's branch does not run (m <= FLOWING): tau over a log grid within TAU_RANGE and
infinity (the reading holds), M over MASS_GRID, each then refined between its grid neighbours;
separately for every replay (the nominal twin and each candidate alike, so they cancel in their
comparison); or the replay's own stagnant fluid (AS_SIMULATED: the twin's own recordings). A value
on a bound of the range is reported. A replay that fits nothing (no training window given) keeps its
own value. "As simulated" is the twin's own recordings: a candidate's replay may read so only where
the calibrated nominal replay does (`nominal`); elsewhere it holds or cools. A candidate that makes
the branch flow leaves it fewer and shorter standstills in training, on which the replay's own
fluid could fit best by chance and then hold a stopped CHP at 80 degC through the held-out days'
two-hour standstills, where the lab's pipe cooled to 36 degC (rigsim realisation 1's
idle_flow_small at the true idle share: 32 standing training samples, the longest 16 min, against
the nominal replay's 93 and 79 min; the CHP outlet's held-out RMSE 5.7 -> 11 K). Kept to the
nominal's reading altogether, a twin-made truth broke: its idle flush, which the nominal replay
lacks, made the nominal's stopped CHP read a cooling, while the candidate that flushes it reads
the twin's held fluid (the concealed idle flow; a hold fits it as well).

The temperature the pipes cool toward (the air around them, not the storage's T_env) is read off
the recording, not fitted in each replay: the lowest of the branches' median readings after
ROOM_AFTER of recorded standstill (plant_room). labsim's pipes cool toward 20 degC, and the house
file's 18 degC left 2 K on all four generator pipe sensors through every long standstill. Fitted
with tau in each replay instead, the nominal twin's idle CHP "cooled toward" 34 degC on labsim's
idle_flow_small, the return water an idle flow makes it read: the asymptote took the evidence.
The lowest branch, because a branch kept warm by a flow nobody recorded reads above the room,
never below it.

Scored samples: all but those at which the recorded flow evidence (the branch's measured flow,
else its command) switches: there the sample's instant within the interval is unknown.
"""
from __future__ import annotations

import hashlib
import math
from typing import NamedTuple

import numpy as np
from numba import njit
from scipy.optimize import minimize, minimize_scalar

FLOWING = 1e-3                 # kg/s: a recorded flow above it is a branch that flows; a simulated
#                                one at or below it carries the fit of tau and M (a running pump moves 20x more)
TAU_RANGE = (300.0, 7200.0)    # s: a bare DN20-40 pipe ... a lagged one with an immersion well
# besides the cooling pipe: inf, the reading holds the last flowing value (a sensor inside the
# unit's body, a logger that holds); AS_SIMULATED (0), the replay's own value of the stagnant
# fluid (the twin's own recordings; also what a replay that fits nothing keeps)
AS_SIMULATED = 0.0
TAU_GRID = np.concatenate([[AS_SIMULATED], np.geomspace(*TAU_RANGE, 14), [np.inf]])
# kg of pipe water upstream of the sensor: a well at the junction ... a metre and a half of DN25
# (at 60 s samples a flow of 0.017 ... 17 g/s renews it within a sample)
MASS_RANGE = (1e-3, 1.0)
MASS_GRID = np.geomspace(*MASS_RANGE, 7)
GRID_DECAYS = np.array([0.0 if math.isinf(tau) else 1.0 / tau for tau in TAU_GRID[1:]])  # 1 / tau
T_PLANT_ROOM_DEFAULT = 20.0    # degC, when the replayed house has no storage stating T_env
ROOM_RANGE = (5.0, 35.0)       # degC: what a pipe may cool toward (a plant room, a cellar, a loft)
ROOM_AFTER = 6 * 3600.0        # s of recorded standstill after which a pipe reads its room (5 tau at
#                                the range's middle; at its longest tau, within 5 % of the step)
MIN_ROOM_SAMPLES = 10


def branches(pipes: dict) -> dict:
    """flow signal -> the sensors on that branch. pipes: sensor -> (its branch's flow signal, the
    command that starts the branch, the command's threshold): the house's (roles.Roles.pipes)."""
    out: dict = {}
    for s, (flow, _, _) in pipes.items():
        out.setdefault(flow, []).append(s)
    return out


def recorded_flowing(rec, signal: str, pipes: dict) -> np.ndarray | None:
    """Samples at which the recording says the sensor's branch flows (None: not a pipe sensor):
    its measured flow > FLOWING when recorded, else its command."""
    if signal not in pipes:
        return None
    flow, cmd, on = pipes[signal]
    if rec.has(flow):
        return np.nan_to_num(rec.data[flow]) > FLOWING
    if rec.has(cmd):
        return np.nan_to_num(rec.data[cmd]) > on
    return None


def scored_mask(rec, measured, pipes: dict) -> np.ndarray:
    """[n, len(measured)]: False at the samples where a pipe sensor's branch starts or stops."""
    out = np.ones((len(rec.time), len(measured)), bool)
    for j, s in enumerate(measured):
        f = recorded_flowing(rec, s, pipes)
        if f is not None:
            out[1:, j] = f[1:] == f[:-1]
    return out


def plant_room(rec, pipes: dict) -> float | None:
    """The temperature the stagnant pipes cool toward, from the recording: per branch, the median
    reading of its sensors at samples ROOM_AFTER or longer after its last recorded flow; the
    lowest branch's, within ROOM_RANGE. None: no branch stands that long."""
    t = rec.time
    out = []
    for sensors in branches(pipes).values():
        f = next((recorded_flowing(rec, s, pipes) for s in sensors if rec.has(s)), None)
        if f is None:
            continue
        last = np.where(f, np.arange(len(t)), -1)
        np.maximum.accumulate(last, out=last)
        since = np.where(last >= 0, t - t[np.maximum(last, 0)], t - t[0])
        long = ~f & (since >= ROOM_AFTER)
        vals = np.concatenate([rec.data[s][long] for s in sensors if rec.has(s)])
        vals = vals[np.isfinite(vals)]
        if vals.size >= MIN_ROOM_SAMPLES:
            out.append(float(np.median(vals)))
    return min(max(min(out), ROOM_RANGE[0]), ROOM_RANGE[1]) if out else None


class PipeFit(NamedTuple):
    """A branch's pipe-sensor model: cooling time constant tau [s] (AS_SIMULATED, a finite value
    or inf) and the pipe water upstream of the sensor mass [kg] (fitted: the branch trickled in
    the fit's samples, else the smallest, which only a trickle could tell from any other)."""
    tau: float
    mass: float
    fitted: bool = False
    borrowed: bool = False   # the branch never stood in the fit's samples: the others' median tau


AS_SIMULATED_FIT = PipeFit(AS_SIMULATED, MASS_RANGE[0])


def cooled(t: np.ndarray, fluid: np.ndarray, m_flow: np.ndarray, fit: PipeFit, T_room: float) -> np.ndarray:
    """The sensor reading: `fluid` renewed by the flow m_flow [kg/s] through fit.mass of pipe water
    that cools toward T_room with fit.tau (before the first sample: the first fluid value);
    tau = AS_SIMULATED: `fluid` throughout."""
    if fit.tau == AS_SIMULATED:
        return fluid
    decay = 0.0 if math.isinf(fit.tau) else 1.0 / fit.tau
    return _reading(np.asarray(t, float), np.asarray(fluid, float), np.nan_to_num(np.asarray(m_flow, float)),
                    float(fit.mass), decay, float(T_room))


@njit(cache=True)
def _reading(t, fluid, m, mass, decay, T_room):
    out = np.empty(t.size)
    T = fluid[0] if np.isfinite(fluid[0]) else T_room
    out[0] = T
    dt_kept, kept = math.nan, 1.0
    for k in range(1, t.size):
        dt = t[k] - t[k - 1]
        if dt != dt_kept:  # a recording's scans are mostly evenly spaced: one exp per spacing
            dt_kept, kept = dt, math.exp(-dt * decay)
        r = min(1.0, max(m[k], 0.0) * dt / mass) if np.isfinite(fluid[k]) else 0.0
        T = r * fluid[k] + (1.0 - r) * (T_room + (T - T_room) * kept)
        out[k] = T
    return out


@njit(cache=True)
def _squares(t, fluid, meas, m, mass, decay, T_room, idx, out):
    """out[i] = (meas - reading)^2 at sample idx[i] (increasing), 0 where NaN (np.nansum's NaN);
    -> out. The reading of _reading, step for step, scored as it goes: no reading array, and
    nothing after the last scored sample."""
    T = fluid[0] if np.isfinite(fluid[0]) else T_room
    i = 0
    if idx.size and idx[0] == 0:
        d = meas[0] - T
        v = d * d
        out[0] = v if v == v else 0.0
        i = 1
    dt_kept, kept = math.nan, 1.0
    for k in range(1, idx[idx.size - 1] + 1 if idx.size else 0):
        dt = t[k] - t[k - 1]
        if dt != dt_kept:
            dt_kept, kept = dt, math.exp(-dt * decay)
        r = min(1.0, max(m[k], 0.0) * dt / mass) if np.isfinite(fluid[k]) else 0.0
        T = r * fluid[k] + (1.0 - r) * (T_room + (T - T_room) * kept)
        if k == idx[i]:
            d = meas[k] - T
            v = d * d
            out[i] = v if v == v else 0.0
            i += 1
    return out


@njit(cache=True)
def _grid_squares(t, fluid, meas, m, masses, decays, T_room, idx, out):
    """_squares for every (decay, mass) pair at once: out[a, b, i] for decays[a], masses[b]. The
    readings of the pairs are independent chains, one pass over the samples advances them all
    (one pair's chain waits on its own previous value; many keep the processor busy); each is
    computed step for step as in _squares, so every square is the same to the last bit. -> out.
    _squares stays for the refinement's single pairs: this kernel given one pair is 3.4x slower
    (its per-sample loops over the pairs), and the refinement asks for a few dozen per fit."""
    na, nb = decays.size, masses.size
    nc = na * nb
    flat = out.reshape(nc, idx.size)
    T0 = fluid[0] if np.isfinite(fluid[0]) else T_room
    T = np.full(nc, T0)
    kept = np.ones(nc)   # the chains' exp(-dt / tau), their r: pair c = a * nb + b
    r = np.empty(nc)
    i = 0
    if idx.size and idx[0] == 0:
        d = meas[0] - T0
        v = d * d
        flat[:, 0] = v if v == v else 0.0
        i = 1
    dt_kept = math.nan
    for k in range(1, idx[idx.size - 1] + 1 if idx.size else 0):
        dt = t[k] - t[k - 1]
        if dt != dt_kept:
            dt_kept = dt
            for a in range(na):
                e = math.exp(-dt * decays[a])
                for b in range(nb):
                    kept[a * nb + b] = e
        finite = np.isfinite(fluid[k])
        for b in range(nb):
            rb = min(1.0, max(m[k], 0.0) * dt / masses[b]) if finite else 0.0
            for a in range(na):
                r[a * nb + b] = rb
        f = fluid[k]
        for c in range(nc):
            T[c] = r[c] * f + (1.0 - r[c]) * (T_room + (T[c] - T_room) * kept[c])
        if k == idx[i]:
            for c in range(nc):
                d = meas[k] - T[c]
                v = d * d
                flat[c, i] = v if v == v else 0.0
            i += 1
    return out


def apply(rec, out: np.ndarray, cols: dict, n: int, T_room: float, t_fit: float | None,
          pipes: dict, nominal: dict | None = None) -> dict:
    """Replace the pipe sensors' columns of the replay rows `out` (first n samples) by their
    modelled reading (cooling toward T_room); tau and mass per branch fitted on the samples up to
    t_fit at which the branch does not run (None: no fit, the replay's own value), as simulated
    only where the nominal replay's fit of the branch (`nominal`: {flow signal: PipeFit}) reads
    so or is not given. cols: catalogue name -> column of the signals the replay computes.
    -> {flow signal: PipeFit}."""
    t = rec.time[:n]
    fit = np.zeros(n, bool) if t_fit is None else (t <= t_fit)
    fits, unseen = {}, {}
    for flow, sensors in branches(pipes).items():
        if flow not in cols or not any(s in cols for s in sensors):
            continue
        m = np.nan_to_num(out[:, cols[flow]])
        sensors = [s for s in sensors if s in cols]
        fluid = {s: out[:, cols[s]].copy() for s in sensors}
        meas = {s: rec.data[s][:n] if rec.has(s) else None for s in sensors}
        use = fit & (m <= FLOWING)
        pf = AS_SIMULATED_FIT
        if use.sum() >= 10 and any(v is not None for v in meas.values()):
            pf = _fit(t, m, use, T_room, [(fluid[s], meas[s]) for s in sensors if meas[s] is not None],
                      (nominal or {}).get(flow, AS_SIMULATED_FIT).tau == AS_SIMULATED)
        elif t_fit is not None and any(v is not None for v in meas.values()):
            unseen[flow] = (m, fluid)
        for s in sensors:
            out[:, cols[s]] = cooled(t, fluid[s], m, pf, T_room)
        fits[flow] = pf
    # a measured branch that never stood while the fit's samples ran (a CHP running through the
    # training days) takes the median cooling of the branches that did: same plant room, the same
    # kind of pipe; the replay's own stagnant fluid would hold the unit's temperature for hours
    cooling = [f.tau for f in fits.values() if 0 < f.tau < math.inf]
    if cooling:
        borrowed = PipeFit(float(np.median(cooling)), MASS_RANGE[0], borrowed=True)
        for flow, (m, fluid) in unseen.items():
            for s, y in fluid.items():
                out[:, cols[s]] = cooled(t, y, m, borrowed, T_room)
            fits[flow] = borrowed
    return fits


def _fit(t, m, use, T_room, pairs, as_simulated: bool = True) -> PipeFit:
    """The (tau, mass) grid's best, refined around it on log scales when finite (a continuous fit:
    a grid step would make every replay's cost jump with it): tau alone by Brent within its grid
    neighbours where the pipe only runs or stands, else both together (Nelder-Mead, within the
    ranges: the two trade off, and one at a time stops short). The same inputs give the fit kept
    from before (_FITS). as_simulated: whether the replay's own fluid is among the readings."""
    # the reading is causal: the samples after the last one scored change no cost. The cost is
    # asked for a few hundred times per replay, so its arrays are prepared once
    end = int(np.flatnonzero(use)[-1]) + 1
    tf, mf, used = np.asarray(t[:end], float), np.nan_to_num(np.asarray(m[:end], float)), use[:end]
    prepared = [(np.asarray(y[:end], float), np.asarray(y_m[:end], float)) for y, y_m in pairs]
    key = hashlib.blake2b(repr((float(T_room), as_simulated)).encode())
    for a in (tf, mf, used, *(a for pair in prepared for a in pair)):
        key.update(np.ascontiguousarray(a).view(np.uint8))
    key = key.digest()
    if key not in _FITS:
        if len(_FITS) >= FITS_KEPT:
            del _FITS[next(iter(_FITS))]
        _FITS[key] = _fit_new(tf, mf, used, T_room, prepared, as_simulated)
    return _FITS[key]


# fits by their inputs' digest: a replay whose branch fluid and flow did not change (a candidate
# on another part of the plant) gets the fit made before (rigsim house 2's 7-day null case: 1,043
# of 3,228 fits, mostly of branches that only stand, the cheap ones)
FITS_KEPT = 256
_FITS: dict = {}


def _fit_new(tf, mf, used, T_room, prepared, as_simulated=True) -> PipeFit:
    """_fit's search on its prepared arrays (cut at the last scored sample)."""
    idx = np.flatnonzero(used)
    scratch = np.empty(idx.size)

    def sse(tau, mass):
        if tau == AS_SIMULATED:
            return sum(float(np.nansum(((y_m - y)[used]) ** 2)) for y, y_m in prepared)
        decay = 0.0 if math.isinf(tau) else 1.0 / tau
        # the squares in one compiled call, summed by numpy as np.nansum sums them (the same
        # pairwise sum: the same cost to the last bit); a third of a replay's time was this cost
        return sum(float(_squares(tf, y, y_m, mf, float(mass), decay, float(T_room), idx, scratch).sum())
                   for y, y_m in prepared)

    moves = bool((mf[used] > 0).any())   # a mass matters only where the pipe trickles
    masses = MASS_GRID if moves else MASS_GRID[:1]
    # the grid's costs, sse's to the last bit: AS_SIMULATED's (one value: no mass), then the
    # other taus' squares in one compiled pass per sensor, each (tau, mass) row summed as sse sums it
    costs = np.empty((TAU_GRID.size, masses.size))
    costs[0] = sse(AS_SIMULATED, masses[0])
    costs[1:] = 0.0
    squares = np.empty((GRID_DECAYS.size, masses.size, idx.size))
    for y, y_m in prepared:
        costs[1:] += _grid_squares(tf, y, y_m, mf, masses, GRID_DECAYS, float(T_room), idx, squares).sum(axis=2)
    if not as_simulated:
        costs[0] = np.inf
    k, j = np.unravel_index(int(np.argmin(costs)), costs.shape)
    tau, mass = float(TAU_GRID[k]), float(masses[j])
    if tau == AS_SIMULATED:
        return AS_SIMULATED_FIT
    if math.isinf(tau):
        if moves:
            mass = _refine(lambda x: sse(tau, x), MASS_GRID, j, mass, costs[k, j])
        return PipeFit(tau, mass, moves)
    if not moves:
        return PipeFit(_refine(lambda x: sse(x, mass), TAU_GRID[1:-1], k - 1, tau, costs[k, j]), mass)
    bounds = [tuple(math.log(b) for b in TAU_RANGE), tuple(math.log(b) for b in MASS_RANGE)]
    res = minimize(lambda u: sse(math.exp(u[0]), math.exp(u[1])), [math.log(tau), math.log(mass)],
                   method="Nelder-Mead", bounds=bounds, options={"xatol": 1e-3, "fatol": 1e-9 * costs[k, j]})
    return PipeFit(*map(math.exp, res.x), True) if res.fun < costs[k, j] else PipeFit(tau, mass, True)


def _refine(cost, grid, k, x, best) -> float:
    """Brent on log x between grid[k]'s neighbours; the grid's x when not better."""
    lo, hi = math.log(grid[max(k - 1, 0)]), math.log(grid[min(k + 1, len(grid) - 1)])
    res = minimize_scalar(lambda u: cost(math.exp(u)), bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    return float(math.exp(res.x)) if res.fun < best else x


def public(fit: PipeFit) -> dict:
    """report.json's entry of a branch's fit."""
    cools = 0 < fit.tau < math.inf
    return {"tau_s": fit.tau if cools else None,
            "reading": "cools" if cools else "holds" if fit.tau else "as simulated",
            "pipe_water_kg": fit.mass if fit.fitted else None, "at_bound": at_bound(fit),
            "tau_from": "the other branches (this one never stood in training)" if fit.borrowed else "fitted"}


def at_bound(fit: PipeFit) -> bool:
    """A cooling time constant on a bound of TAU_RANGE."""
    return bool(0 < fit.tau < math.inf and min(abs(math.log(fit.tau / b)) for b in TAU_RANGE) < 1e-2)
