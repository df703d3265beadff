"""Fit every plausible candidate on the training window, judge it on the held-out window, select.

Simulate-kind candidates: a coarse grid over the (log-)bounded parameter, then a bounded Brent
search (scipy.optimize.minimize_scalar) in the best grid bracket, each evaluation a replay of the
training window only; the winner is replayed over the whole recording once. Signal-kind
candidates are fitted per measured signal on the cached nominal replay (no re-simulation); the
signal whose residual the effect removes by the largest share is kept (a storage sensor's relative
to its neighbours, common_mode).

Judging and selection: verdict.py.

Calibration of the nominal structure (the re-fit, the storage scheme, identifiability):
calibration.py; bounded searches: bounded.py; a simulate candidate's memoised training cost and
its passes over the parameters: sim_fit.py.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .sensor_height import placed
from .bounded import at_bound, descent, scalar_search
from .sim_fit import (TrainingCost, along, local_pass, own as _own, rechoose_scheme, stderr as _stderr,
                      without_unidentified)

JOINT_REFIT = True   # re-fit the nominal knobs (calibration.knobs) jointly with each simulate candidate (else: kept fixed)


@dataclass(frozen=True)
class Result:
    """One candidate's fit; judging it (verdict.judge) or placing it on top of another effect
    (forward.py) gives a new Result (dataclasses.replace)."""
    id: str
    component: str
    kind: str
    plausible: bool
    reason: str = ""
    theta: list = field(default_factory=list)
    stderr: list = field(default_factory=list)
    signal: str | None = None
    train_cost: float = math.nan
    held_cost: float = math.nan
    held_gain: float = math.nan
    bic: float = math.nan
    accepted: bool = False
    evaluations: int = 0
    sim: np.ndarray | None = None      # [n, n_measured] fitted simulation of the measured signals
    rows: np.ndarray | None = None     # full catalogue rows (simulate kind) for energies/plots
    effect: object = None
    k: int = 1                         # number of fitted parameters (BIC)
    at_bound: list = field(default_factory=list)  # fitted parameters that ended on a bound
    local: dict | None = None          # a sensor candidate judged relative to its neighbours (fit_signal)
    nominal: dict = field(default_factory=dict)  # jointly re-fitted nominal parameters
    pipe: dict = field(default_factory=dict)     # its replay's pipe-sensor fits (pipe_sensor.PipeFit per branch)
    refitted_with: str | None = None   # a sensor effect fitted again on the model with this plant effect (forward.py)
    fit_note: str = ""                 # why the fit took another way than the usual (stops_running)

    def public(self) -> dict:
        return {"id": self.id, "component": self.component if self.signal is None else self.signal,
                "kind": self.kind, "plausible": self.plausible, "reason": self.reason,
                "parameters": {p.name: {"value": float(v), "stderr": float(s), "unit": p.unit,
                                        "nominal": p.nominal}
                               for p, v, s in zip(self.effect.params, self.theta, self.stderr)},
                "signal": self.signal, "train_cost": self.train_cost, "heldout_cost": self.held_cost,
                "heldout_gain": self.held_gain, "bic": self.bic, "accepted": self.accepted,
                "evaluations": self.evaluations, "nominal_refit": dict(self.nominal),
                "parameters_at_bound": list(self.at_bound), "relative_to_neighbours": self.local,
                "fit_note": self.fit_note}


def stops_running(ctx, rows) -> str:
    """'' unless the replay `rows` has a unit stand (unit_modes.identify: the recording's unit
    runs, the replay's does not) at more than unit_modes.MAX_SHARE of the samples at which the
    recording shows it running, and at more than twice the nominal replay's share; else which."""
    from .unit_modes import MAX_SHARE, identify

    now = identify(ctx.rec, rows, ctx.index, ctx.roles.ran)
    before = identify(ctx.rec, ctx.nominal.rows, ctx.index, ctx.roles.ran) if ctx.nominal is not None else {}
    for unit, m in now.items():
        if not m["lab_runs"]:
            continue
        share = m["lab_runs_twin_not"] / m["lab_runs"]
        nominal = before[unit]["lab_runs_twin_not"] / m["lab_runs"] if unit in before else 0.0
        if share > max(MAX_SHARE, 2.0 * nominal):
            return (f"{unit} stands at {share * 100:.0f} % of the samples where the recording has it running "
                    f"(the nominal replay at {nominal * 100:.0f} %)")
    return ""


def fit_simulate(effect, ctx, replayer, nominal_cost, nominal=None) -> Result:
    """1 fitted parameter: grid + Brent. Several (effect.fitted(ctx)): coordinate descent - each
    parameter by grid + Brent with the others held, then a second, local pass (bracket +-15 % of
    the range) over all of them; the parameters not fitted stay nominal.
    nominal: Params of the nominal re-fit (refit_nominal), held at their file values during the
    candidate's own fit; with JOINT_REFIT they are then re-fitted within their bounds (one pass),
    followed by a local pass over the candidate's parameters. A key the candidate sets itself is
    left to the candidate."""
    params = effect.params
    free = effect.fitted(ctx)
    own = set(effect.overrides([p.nominal for p in params]))
    nom = [q for q in (nominal or []) if q.name not in own] if JOINT_REFIT else []
    ne = len(params)
    F = TrainingCost(effect, ctx, replayer, nom)
    # the candidate is fitted with the nominals at their FILE values first (the baseline's
    # re-fit has already bent them towards the missing effect: starting there, the candidate
    # came out 16 % small on a 40 W/K storage loss and the joint pass stalled at 10x the cost)
    theta = [p.nominal for p in params] + [q.nominal for q in nom]
    J = _own(F, params, free, theta)
    if nom:
        th, Jn, _ = descent(F, list(params) + nom, theta, range(ne, ne + len(nom)), maxiter=5)
        if Jn < J:
            theta[:], J = th, Jn
            J = local_pass(F, params, free, theta, J)
    if "storage" in replayer.instances() - replayer.calibrated:
        # a candidate acting on the storage (a port plume) trades off against how finely the
        # tank resolves its thermocline: the scheme is chosen again with the candidate fitted
        Js = rechoose_scheme(F, replayer, theta, J)
        if Js < J:
            J = local_pass(F, params, free, theta, Js)
    run, note = replayer.run(F.overrides(theta)), ""
    if nom and (stops := stops_running(ctx, run.rows)):
        # the jointly re-fitted nominals carried the candidate where the twin's unit stands while
        # the recording's runs (rigsim house 3's ground collector at UA x 0.39 with the heat pump's
        # nominal heat re-fitted up: on the held-out days its brine fell to the -5 degC limit,
        # where the rig's ran at -2 degC, and the unit cycled between lock-out and start-up):
        # such a replay explains no recording, so the candidate is fitted again with the
        # nominals held at the baseline's calibrated values
        F, nom = TrainingCost(effect, ctx, replayer, []), []
        note = f"with the nominal knobs re-fitted jointly, {stops}: fitted again with them held at the calibrated values"
        theta = [p.nominal for p in params]
        J = _own(F, params, free, theta)
        run = replayer.run(F.overrides(theta))
    n_eff = ctx.n_eff(ctx.train)
    se = [_stderr(along(F, theta, i), params[i], theta[i], J, n_eff) if i in free else math.nan
          for i in range(len(params))]
    if (fewer := without_unidentified(F, params, free, theta, J, se, n_eff)) is not None:
        dropped = ", ".join(f"{params[i].name} {theta[i]:.3g} +- {se[i]:.2g}" for i in free if i not in fewer[0])
        note = (note + "; " if note else "") + f"{dropped} not told from nominal: fitted without it (better BIC)"
        free, theta, J, se = fewer
        run = replayer.run(F.overrides(theta))
    rows = run.rows
    sim = rows[:, ctx.cols]
    return Result(effect.id, effect.component, effect.kind, True, theta=list(theta[:ne]), stderr=se,
                  train_cost=ctx.cost(sim, ctx.train), held_cost=ctx.cost(sim, ctx.held),
                  evaluations=len(F.cache) + 1, sim=sim, rows=rows, effect=effect,
                  nominal={**{q.name: float(v) for q, v in zip(nom, theta[ne:])}, **F.scheme},
                  pipe=dict(run.pipe), k=len(free), fit_note=note)


NEAR = 0.15  # relative tank height within which a sensor is a neighbour (10 sensors: 0.1 apart)


def neighbours(ctx, j) -> list[int]:
    """The measured sensors of the same storage array next to sensor j (the nearest below and
    above it within NEAR of its height); [] for any other signal."""
    arr, sep, i = ctx.measured[j].rpartition(".T_sensor_")
    if not sep or not i.isdigit():
        return []
    have = {int(x.rpartition("_")[2]): k for k, x in enumerate(ctx.measured) if x.startswith(arr + sep)}
    n = max(10, max(have))
    z = {k: ctx.rec.heights.get(f"{arr}{sep}{k}", (k - 0.5) / n) for k in have}  # relative heights
    near = [k for k in have if k != int(i) and abs(z[k] - z[int(i)]) <= NEAR]
    below, above = [k for k in near if k < int(i)], [k for k in near if k > int(i)]
    return ([have[max(below)]] if below else []) + ([have[min(above)]] if above else [])


def common_mode(ctx, nominal_sim, j):
    """The residual sensor j shares with its neighbours (their mean residual at each sample),
    None without neighbours. A sensor effect is the sensor's own; a plant-model difference (a
    storage a few K warmer in the lab than in the twin) moves the neighbours alike. A sensor
    candidate is fitted and judged on the sensor's residual relative to its neighbours', so a
    structural bias neither hides a sensor offset (a -3 K offset on a tank the twin runs 3 K too
    cold leaves no absolute residual) nor poses as one."""
    nb = neighbours(ctx, j)
    if not nb:
        return None
    r = ctx.residual(nominal_sim)[:, nb]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nan_to_num(np.nanmean(r, axis=1))


# a sensor candidate on a storage sensor removes >= this share of its residual relative to its
# neighbours (labsim's no-effect case: at most 27 %; a 1.5 K offset or a 300 s lag: 40 %); here on
# the training window to pick the signal, in verdict._judge_local on the held-out window
LOCAL_GAIN = 0.35


class _Tried(NamedTuple):
    """A sensor candidate fitted on one signal (fit_signal)."""
    key: tuple           # (local and its share passes LOCAL_GAIN, share of its residual removed)
    j: int               # column of the signal
    value: float         # the fitted parameter
    cost: object         # value -> training MSE on the signal
    y0: np.ndarray       # the twin's value the effect acts on
    local: bool          # judged on its own (relative) residual
    y_before: np.ndarray  # that value before any joint radiator re-fit
    removed: float       # residual removed [unit^2]
    tank: str | None     # the storage of a storage sensor


def fit_signal(effect, ctx, nominal_sim, replayer=None, only: str | None = None) -> Result:
    """Fit a post-processing candidate to each eligible signal; keep the one whose own residual
    it reduces by the largest share on training (a sensor effect explains its sensor's residual
    nearly whole; a structural difference it imitates, only in part). On a storage sensor the effect acts on the twin's
    value plus the neighbours' common residual (common_mode) and is judged there (Result.local);
    on the return of the emitter replayed alone (replayer given) it is fitted jointly with the
    emitter's calibrated parameters and judged on that return alone (Result.local). only: fit
    on that signal alone (a sensor effect fitted again on another model's reading)."""
    tried = []
    nfev = 0
    hc = replayer.heating if replayer is not None else None
    alone = set(hc.emitter_outputs) if hc is not None and hc.emitter in replayer.calibrated else set()
    for j, s in enumerate(ctx.measured):
        if ctx.unit(s) not in effect.signal_units or (only is not None and s != only):
            continue
        one, k = _try_signal(effect, ctx, nominal_sim, replayer, j, s in alone)
        nfev += k
        if one is not None:
            tried.append(one)
    if not tried:
        return Result(effect.id, effect.component, effect.kind, False, "no eligible measured signal",
                      effect=effect)
    # a storage sensor whose residual has another shape than the effect's (Effect.unlike) is not
    # its signal: the next one is (rigsim house 2's sensor 2 at a port, +2.8 K with the heat pump
    # on and -3.0 K with it off, took the offset candidate from a -2 K offset on sensor 4)
    # nor is one where its value ends on a bound of its range (rigsim house 2's sensor 1, a
    # 3600 s "lag" removing 35 % of a 3.3 K residual, took the candidate from sensor 9's 600 s)
    return _signal_result(effect, ctx, nominal_sim,
                          _best_tried(tried, lambda x: not _unlike(effect, ctx, x)
                                      and not at_bound(effect.params[0], x.value)), nfev, alone)


def _fit_on(effect, ctx, j, hf, y0, m):
    """The candidate fitted on signal j's first len(y0) samples, acting on the twin's value y0,
    on mask m -> (value, training MSE, evaluations, the MSE as a function of the value)."""
    p = effect.params[0]
    n = len(y0)
    mm, meas, tn = m[:n], ctx.meas[:n, j], ctx.rec.time[:n]

    def f(v):
        return float(np.mean((meas[mm] - placed(meas, effect.apply(tn, y0, [v]), mm, hf)[mm]) ** 2))
    v = effect.solve(meas - y0, mm, hf)
    if v is not None:
        v = float(np.clip(v, p.lo, p.hi))
        return v, f(v), 1, f
    return scalar_search(f, p, n_grid=5, maxiter=8) + (f,)


def _try_signal(effect, ctx, nominal_sim, replayer, j, alone: bool) -> tuple[_Tried | None, int]:
    """The candidate fitted on measured signal j on the training window -> (_Tried, or None with
    fewer than 10 usable training samples; evaluations). alone: j is the return of the emitter
    replayed alone."""
    s = ctx.measured[j]
    c = common_mode(ctx, nominal_sim, j)
    y0 = nominal_sim[:, j] + (c if c is not None else 0.0)
    m = ctx.train & ctx.ok[:, j]
    if m.sum() < 10:
        return None, 0
    # a storage sensor's place within its tolerance is fitted again with the candidate
    # (sensor_height.py): the twin's reading before the nominal's shift
    hf = ctx.heights.get(s) if c is not None else None
    if hf is not None:
        y0 = y0 - hf.shift * hf.g

    def fit_on(y0, m=m):
        return _fit_on(effect, ctx, j, hf, y0, m)

    y_before = placed(ctx.meas[:, j], y0, m, hf)
    v, J, nfev, f = fit_on(y0)
    if alone:
        # the emitter replayed alone: its rating, water content and element count are
        # re-fitted jointly with the candidate (a larger radiator delays its return too:
        # calibrated without the candidate it absorbs part of a sensor's delay). Each radiator
        # the re-fit tries takes the candidate's best value for it (one parameter over a
        # return: cheap), so the pair is fitted as one; alternating fits crept towards it
        # (labsim spring, a 600 s delay: 303, 395, 459, 501, 529, 546 s in six alternations)
        def joint(y, m=m & replayer.circuit_flowing(settled=True)):
            return effect.apply(ctx.rec.time[:len(y)], y, [fit_on(y, m)[0]])

        vals, N = replayer.refit_emitter(joint, ctx.train)
        y0 = replayer.emitter_return(vals, N, ctx.nominal.pipe)
        v, J, k, f = fit_on(y0)
        nfev += k
    J0 = float(np.mean((ctx.meas[m, j] - y_before[m]) ** 2))
    red = (J0 - J) / max(J0, 1e-12)  # the share of the signal's own residual the effect removes
    # a storage sensor's share is of its residual relative to its neighbours, the return of a
    # subsystem replayed alone of its residual there, another signal's of its whole residual
    # (a structural bias included): a local one whose share would pass LOCAL_GAIN goes first
    local = c is not None or alone
    key = (local and red >= LOCAL_GAIN, red)
    return _Tried(key, j, v, f, y0, local, y_before, J0 - J,
                  s.rpartition(".T_sensor_")[0] if c is not None else None), nfev


def _best_tried(tried: list, like=lambda x: True) -> _Tried:
    """The signal a sensor candidate is named on, among those `like` accepts (all when none)."""
    pool = [x for x in tried if like(x)] or tried
    best = max(pool, key=lambda x: x.key)
    if best.tank is not None and best.key[0]:
        # among the sensors of that storage that pass, the one whose residual it removes most in
        # K^2: an offset d on one sensor leaves -d/2 on each neighbour's relative residual, which
        # an offset removes as wholly (by the share alone, labsim's +1.5 K on sensor 5 was once
        # fitted as -0.72 K on sensor 6)
        best = max((x for x in pool if x.tank == best.tank and x.key[0]), key=lambda x: x.removed)
    return best


def _unlike(effect, ctx, x: _Tried) -> str:
    """Effect.unlike on a storage sensor's training residual relative to its neighbours, in every
    operating state (Roles.states); '' for any other signal. The residual is the one the effect's
    model leaves plus what the effect gives: with the sensor's place fitted together with the
    effect, as the effect was fitted (SensorOffset.solve). Placed without it, the place takes
    part of a true offset where the tank's gradient is steep: labsim realisation 3's -3 K offset
    on sensor 5 kept only 0.41 of itself with the CHP off, and the offset was not named."""
    if x.tank is None:
        return ""
    s = ctx.measured[x.j]
    if effect.same_in_every_state and s in ctx.unrepresented:
        # the nominal replay leaves this sensor beyond its limit with both signs by state: a
        # sensor at a port the twin's layers do not resolve, where one value cannot be its error
        # (rigsim house 2's null_a: +5.15 K on sensor 2, read +2.8 K with the heat pump on and
        # -3.0 K off, passed the shape check below once its place was fitted with it)
        return f"{s} cannot be represented by the twin: {ctx.unrepresented[s]['why']}"
    m = ctx.train & ctx.ok[:, x.j]
    meas = ctx.meas[:, x.j]
    y1 = effect.apply(ctx.rec.time[:len(x.y0)], x.y0, [x.value])
    e = meas[:len(y1)] - placed(meas, y1, m, ctx.heights.get(ctx.measured[x.j])) + (y1 - x.y0)
    mm = m[:len(e)]
    return effect.unlike([x.value], e[mm], {k: f[:len(mm)][mm] for k, f in ctx.states.items()})


def _signal_result(effect, ctx, nominal_sim, best: _Tried, nfev: int, alone: set) -> Result:
    """The chosen signal's fit over the whole recording as a Result (its standard error; judged
    on its own residual: Result.local)."""
    p = effect.params[0]
    j, v, f, y0, local, y_before = best.j, best.value, best.cost, best.y0, best.local, best.y_before
    sim = nominal_sim.copy()
    m = ctx.train & ctx.ok[:, j]
    hf = ctx.heights.get(ctx.measured[j]) if best.tank is not None else None
    sim[:, j] = placed(ctx.meas[:, j], effect.apply(ctx.rec.time, y0, [v]), m, hf)
    se = effect.stderr(ctx.meas[m, j] - sim[m, j], ctx.n_eff(ctx.train))
    if se is None:
        se = _stderr(f, p, v, f(v), ctx.n_eff(ctx.train))
    judged_on = _judged_on(ctx, j, y_before, sim, alone) if local else None
    if best.tank is not None:
        # relative to its neighbours a storage sensor's residual is its own: the effect's shape
        # there in every operating state (Effect.unlike)
        judged_on["unlike"] = _unlike(effect, ctx, best)
    return Result(effect.id, "sensor", effect.kind, True, theta=[v], stderr=[se], signal=ctx.measured[j],
                  train_cost=ctx.cost(sim, ctx.train), held_cost=ctx.cost(sim, ctx.held),
                  evaluations=nfev, sim=sim, effect=effect, local=judged_on)


def _judged_on(ctx, j, y_before, sim, alone: set) -> dict:
    """Result.local of a sensor candidate judged on signal j's own residual: its held-out RMS
    before and after, the share removed, the mismatch limit and the neighbours it is relative to."""
    h = ctx.held & ctx.ok[:, j]
    e0, e1 = ctx.meas[h, j] - y_before[h], ctx.meas[h, j] - sim[h, j]
    judged_on = {"heldout_rms_before": float(np.sqrt(np.mean(e0 ** 2))),
                 "heldout_rms_after": float(np.sqrt(np.mean(e1 ** 2))),
                 "gain": 1.0 - float(np.mean(e1 ** 2)) / max(float(np.mean(e0 ** 2)), 1e-12),
                 "limit": ctx.limit(j),
                 "neighbours": [ctx.measured[k] for k in neighbours(ctx, j)]}
    if ctx.measured[j] in alone:
        # calibrated on this very signal, the subsystem alone has no structural allowance to
        # keep: its residual is a mismatch above the sensor's noise (3 sigma)
        judged_on["what"] = f"{ctx.measured[j]} (emitter replayed alone, re-fitted with the candidate)"
        judged_on["limit"] = ctx.limit(j, tol=0.0)
    return judged_on
