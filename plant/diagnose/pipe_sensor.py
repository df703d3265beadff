"""A temperature sensor on a pipe that stands still: modelled, so it can carry evidence.

A sensor in a pipe reads its fluid only while the fluid flows. When the branch stands, the water
at the sensor cools toward the plant room (Newton cooling of the stagnant pipe water), which the
twin's generator (it holds its outlet at the last running value) does not model. The replay's
reading of such a sensor therefore follows the branch's *simulated* flow: the fluid temperature
while it flows, else an exponential from the last flowing value toward the plant-room temperature
(the replayed house's `storage.T_env`) with time constant tau.

Why a model and not a mask: which branch flows is itself what some missing physics changes. An
idle CHP that a header short-circuit keeps flowing reads the return water in the lab, while a
stagnant twin CHP reads a cooled pipe: masked, that difference (the clearest sign of the idle
flow) was invisible; modelled, the candidate that makes the twin's CHP branch flow removes it.

tau (a pipe's insulation, diameter and the sensor's well, not on any data sheet) is calibrated
per branch on the training window only, over a log grid within TAU_RANGE and infinity (the
reading holds), separately for every replay (the nominal twin and each candidate alike, so it
cancels in their comparison), or the reading holds, or it is the replay's own stagnant fluid
(AS_SIMULATED: the twin's own recordings); a value on a bound of the range is reported. A replay
that fits nothing (no training window given) keeps its own value.

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

import math

import numpy as np
from scipy.optimize import minimize_scalar

# sensor -> (its branch's flow signal, the command that starts the branch, command threshold)
STAGNANT_PIPE = {
    "chp.T_sup": ("chp.m_flow", "chp.on", 0.5), "chp.T_ret": ("chp.m_flow", "chp.on", 0.5),
    "boiler.T_sup": ("boiler.m_flow", "boiler.U_set", 2.0), "boiler.T_ret": ("boiler.m_flow", "boiler.U_set", 2.0),
    "mixer.T_sup": ("mixer.m_flow", "mixer.m_flow_set", 0.005), "mixer.T_ret": ("mixer.m_flow", "mixer.m_flow_set", 0.005),
}
FLOWING = 1e-3                 # kg/s
TAU_RANGE = (300.0, 7200.0)    # s: a bare DN20-40 pipe ... a lagged one with an immersion well
# besides the cooling pipe: inf, the reading holds the last flowing value (a sensor inside the
# unit's body, a logger that holds); AS_SIMULATED (0), the replay's own value of the stagnant
# fluid (the twin's own recordings; also what a replay that fits nothing keeps)
AS_SIMULATED = 0.0
TAU_GRID = np.concatenate([[AS_SIMULATED], np.geomspace(*TAU_RANGE, 14), [np.inf]])
T_PLANT_ROOM_DEFAULT = 20.0    # degC, when the replayed house has no storage stating T_env
ROOM_RANGE = (5.0, 35.0)       # degC: what a pipe may cool toward (a plant room, a cellar, a loft)
ROOM_AFTER = 6 * 3600.0        # s of recorded standstill after which a pipe reads its room (5 tau at
#                                the range's middle; at its longest tau, within 5 % of the step)
MIN_ROOM_SAMPLES = 10


def branches() -> dict:
    """flow signal -> the sensors on that branch."""
    out: dict = {}
    for s, (flow, _, _) in STAGNANT_PIPE.items():
        out.setdefault(flow, []).append(s)
    return out


def recorded_flowing(rec, signal: str) -> np.ndarray | None:
    """Samples at which the recording says the sensor's branch flows (None: not a pipe sensor):
    its measured flow > FLOWING when recorded, else its command."""
    if signal not in STAGNANT_PIPE:
        return None
    flow, cmd, on = STAGNANT_PIPE[signal]
    if rec.has(flow):
        return np.nan_to_num(rec.data[flow]) > FLOWING
    if rec.has(cmd):
        return np.nan_to_num(rec.data[cmd]) > on
    return None


def scored_mask(rec, measured) -> np.ndarray:
    """[n, len(measured)]: False at the samples where a pipe sensor's branch starts or stops."""
    out = np.ones((len(rec.time), len(measured)), bool)
    for j, s in enumerate(measured):
        f = recorded_flowing(rec, s)
        if f is not None:
            out[1:, j] = f[1:] == f[:-1]
    return out


def plant_room(rec) -> float | None:
    """The temperature the stagnant pipes cool toward, from the recording: per branch, the median
    reading of its sensors at samples ROOM_AFTER or longer after its last recorded flow; the
    lowest branch's, within ROOM_RANGE. None: no branch stands that long."""
    t = rec.time
    out = []
    for sensors in branches().values():
        f = next((recorded_flowing(rec, s) for s in sensors if rec.has(s)), None)
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


def cooled(t: np.ndarray, fluid: np.ndarray, flowing: np.ndarray, tau: float, T_room: float) -> np.ndarray:
    """The sensor reading: `fluid` while flowing, else the last flowing value relaxing toward
    T_room with time constant tau (before the first flowing sample: from the first value);
    tau = AS_SIMULATED: `fluid` throughout."""
    if tau == AS_SIMULATED:
        return fluid
    n = len(t)
    last = np.where(flowing, np.arange(n), 0)
    np.maximum.accumulate(last, out=last)
    start = np.nan_to_num(fluid[last], nan=T_room)
    decay = T_room + (start - T_room) * np.exp(-(t - t[last]) / tau)
    return np.where(flowing, fluid, decay)


def apply(rec, out: np.ndarray, cols: dict, n: int, T_room: float, t_fit: float | None) -> dict:
    """Replace the pipe sensors' columns of the replay rows `out` (first n samples) by their
    modelled reading (cooling toward T_room); tau per branch fitted on the samples up to t_fit
    (None: no fit, the replay's own value). cols: catalogue name -> column of the signals the
    replay computes. -> {flow signal: tau}."""
    t = rec.time[:n]
    fit = np.zeros(n, bool) if t_fit is None else (t <= t_fit)
    taus = {}
    for flow, sensors in branches().items():
        if flow not in cols or not any(s in cols for s in sensors):
            continue
        f = np.nan_to_num(out[:, cols[flow]]) > FLOWING
        sensors = [s for s in sensors if s in cols]
        fluid = {s: out[:, cols[s]].copy() for s in sensors}
        meas = {s: rec.data[s][:n] if rec.has(s) else None for s in sensors}
        use = fit & ~f
        tau = AS_SIMULATED
        if use.sum() >= 10 and any(m is not None for m in meas.values()):
            tau = _fit_tau(t, f, use, T_room, [(fluid[s], meas[s]) for s in sensors if meas[s] is not None])
        for s in sensors:
            out[:, cols[s]] = cooled(t, fluid[s], f, tau, T_room)
        taus[flow] = tau
    return taus


def _fit_tau(t, flowing, use, T_room, pairs) -> float:
    """The grid's best, refined within its neighbours on log tau when finite (a continuous fit:
    a grid step would make every replay's cost jump with it)."""
    def sse(tau):
        return sum(float(np.nansum(((m - cooled(t, y, flowing, tau, T_room))[use]) ** 2)) for y, m in pairs)

    costs = [sse(tau) for tau in TAU_GRID]
    k = int(np.argmin(costs))
    tau = float(TAU_GRID[k])
    if 0 < tau < math.inf:
        lo, hi = math.log(TAU_GRID[max(k - 1, 1)]), math.log(TAU_GRID[min(k + 1, len(TAU_GRID) - 2)])
        res = minimize_scalar(lambda u: sse(math.exp(u)), bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-3})
        if res.fun < costs[k]:
            tau = float(math.exp(res.x))
    return tau


def at_bound(tau: float) -> bool:
    """A cooling time constant on a bound of TAU_RANGE."""
    return bool(0 < tau < math.inf and min(abs(math.log(tau / b)) for b in TAU_RANGE) < 1e-2)
