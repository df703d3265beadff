"""Fit every plausible candidate on the training window, judge it on the held-out window, select.

Simulate-kind candidates: a coarse grid over the (log-)bounded parameter, then a bounded Brent
search (scipy.optimize.minimize_scalar) in the best grid bracket, each evaluation a replay of the
training window only; the winner is replayed over the whole recording once. Signal-kind
candidates are fitted per measured signal on the cached nominal replay (no re-simulation); the
signal whose residual the effect removes by the largest share is kept (a storage sensor's relative
to its neighbours, common_mode).

Judging and selection: verdict.py.

Nominal re-fit (NOMINAL_REFIT): a few nominal twin parameters that are uncertain in the house
file but matter for replay are re-fitted within narrow bounds (+-10..15 % of the file value) on
the training window, (1) for the nominal model alone, so the "before" baseline is the best nominal
twin (refit_nominal), and (2) jointly with each simulate-kind candidate's own parameters (one
bounded Brent pass over them after the candidate's fit, then a local pass over the candidate's
parameters again). The narrow bounds keep them from soaking up a missing effect. They count for
the nominal model and every candidate alike, so they cancel in the BIC comparison. A candidate
that fits one of them itself (heat_loss: storage.UA_loss) keeps its own, wide-range, value.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar

from .effects.base import Param



@dataclass(frozen=True)
class NominalParam:
    key: str          # house-file override "section.key"
    rel: float        # bounds: file value * (1 -+ rel)
    unit: str
    why: str
    bounds: tuple | None = None  # absolute bounds instead (a file value of 0: the ideal)


# Uncertain in the house file, and each sets a replayed signal directly while the commands are
# replayed (bounds narrow on purpose: an effect the twin lacks must not hide in them):
NOMINAL_REFIT = (
    NominalParam("storage.UA_loss", 0.15, "W/K",
                 "storage standby loss (insulation, plant-room temperature): the slope of all ten "
                 "storage sensors while no generator runs"),
    NominalParam("radiator.Q_nominal", 0.10, "W",
                 "radiator size (rating, valve settings): with the mixer set-points replayed it sets "
                 "the heating return temperature, hence the storage bottom and switch return"),
    NominalParam("zone.H_direct", 0.10, "W/K",
                 "room-to-outdoor conductance (ventilation, leakage): the room temperature and, "
                 "through it, the radiator emission"),
    NominalParam("switch.storage_inlet_mixing", 0.0, "m3",
                 "the inlet zone any real tank has at its ports and the file's ideal (0) lacks: up to "
                 "50 l (2.5 of the file's 20 l layers); the storage_mixing candidate fits a plume "
                 "beyond it. labsim's tank with no plume looks like 53 l on an upwind 80-layer twin "
                 "(11 % of the held-out cost); 100 l, as before the storage scheme was calibrated, "
                 "hid a 120 l plume", bounds=(0.0, 0.05)),
)
# How finely the storage resolves its thermocline, chosen before the re-fit (a discrete choice):
# an independent tank's stratification spreads as its own discretisation and mixing make it.
# The file's scheme is sharp (superbee, 40 layers); the storage kernel also offers the original
# ProHMo model's first-order upwind scheme, whose numerical dispersion (about one layer per
# passage of a front) is set by the layer count. Port mixing (switch.storage_inlet_mixing) is the
# wrong shape for that (it was re-fitted up to 100 l before, now up to 50 l as an inlet zone):
# it smears only the inlet
# layers, so a sensor near a port responds too slowly and hides its own lag (labsim
# sensor_lag_300: the top sensor's 300 s lag gained 0-25 % on the sharp tank with 72-82 l of
# port mixing, 56-64 % on an upwind tank; none on no_effect). A port plume stays a candidate
# (storage_mixing), fitted with the scheme chosen again jointly (fit_simulate).
STORAGE_SCHEMES = (
    ("file (superbee, 40 layers)", {}),
    ("upwind, 20 layers", {"storage.limiter": 0, "storage.n_layers": 20}),
    ("upwind, 30 layers", {"storage.limiter": 0, "storage.n_layers": 30}),
    ("upwind, 50 layers", {"storage.limiter": 0, "storage.n_layers": 50}),
    ("upwind, 80 layers", {"storage.limiter": 0, "storage.n_layers": 80}),
)
JOINT_REFIT = True   # re-fit NOMINAL_REFIT jointly with each simulate candidate (else: kept fixed)


def nominal_params(house: str, refit=NOMINAL_REFIT, instances=None) -> list:
    """Param objects (name = override key, bounds = file value -+ rel) of the re-fitted nominals
    (instances: those the replay has, Replayer.instances(); a cut replaces the radiator and the
    room by measurements, so their parameters are not re-fitted there)."""
    from ..declaration import load

    spec = load(house)
    out = []
    for q in refit:
        section, _, key = q.key.partition(".")
        if instances is not None and section not in instances:
            continue
        inst = spec.instances[section]
        if q.bounds is not None:
            v = float(getattr(inst.params, key)) if hasattr(inst.params, key) else float(inst.options.get(key) or 0.0)
            out.append(Param(q.key, q.bounds[0], q.bounds[1], min(max(v, q.bounds[0]), q.bounds[1]), q.unit))
            continue
        v = float(getattr(inst.params, key))
        out.append(Param(q.key, v * (1.0 - q.rel), v * (1.0 + q.rel), v, q.unit))
    return out


def at_bound(p, v) -> bool:
    """Whether a fitted value ends on a bound of its search range (in the search's scale): the
    data asked for more than the parameter may give."""
    lo, hi, u = _to_u(p, p.lo), _to_u(p, p.hi), _to_u(p, max(v, p.lo) if p.log else v)
    return bool(min(u - lo, hi - u) <= 2e-3 * (hi - lo))


def _descent(F, params, theta, idx, maxiter=6, n_grid=3):
    """One coordinate pass: each parameter in idx by a coarse grid + bounded Brent over its whole
    (narrow) range, the others held. -> (theta, cost, evaluations)."""
    theta = list(theta)
    J = F(theta)
    nfev = 1
    for i in idx:
        p = params[i]

        def f(v, i=i):
            th = list(theta)
            th[i] = v
            return F(th)

        v, Jv, k = _scalar_search(f, p, n_grid=n_grid, maxiter=maxiter)
        nfev += k
        if Jv < J:
            theta[i], J = v, Jv
    return theta, J, nfev


def refit_nominal(ctx, replayer, house: str, refit=NOMINAL_REFIT) -> dict:
    """Fit the nominal re-fit parameters of the nominal model (no candidate) on the training
    window; sets replayer.base to them (every later replay starts from them). -> report entry."""
    params = nominal_params(house, refit, replayer.instances() - replayer.calibrated)
    refit = [q for q in refit if q.key in {p.name for p in params}]
    t_end = float(ctx.rec.time[ctx.train].max())
    scheme = choose_storage_scheme(ctx, replayer, t_end)
    if not params:
        return {"parameters": [], "train_cost_file": math.nan, "train_cost_refit": math.nan,
                "storage_scheme": scheme}
    cache = {}

    def F(theta):
        key = tuple(round(float(v), 9) for v in theta)
        if key not in cache:
            rows = replayer.run({p.name: float(v) for p, v in zip(params, theta)}, until=t_end)
            cache[key] = ctx.cost(rows[:, ctx.cols], ctx.train)
        return cache[key]

    theta0 = [p.nominal for p in params]
    J_file = F(theta0)
    theta, J, _ = _descent(F, params, theta0, range(len(params)))
    replayer.base = {**replayer.base, **{p.name: float(v) for p, v in zip(params, theta)}}
    rows = []
    for p, q, v in zip(params, refit, theta):
        rows.append({"name": p.name, "file_value": p.nominal, "fitted_value": float(v),
                     "change_pct": 100.0 * (v / p.nominal - 1.0) if p.nominal else math.nan,
                     "bounds": [p.lo, p.hi], "unit": p.unit,
                     "at_bound": at_bound(p, v) and not (q.bounds is not None and v == p.nominal), "why": q.why})
    ident = identifiability(F, [p.name for p in params], [p.lo for p in params], [p.hi for p in params],
                            theta, ctx.n_eff(ctx.train))
    return {"parameters": rows, "train_cost_file": J_file, "train_cost_refit": J,
            "evaluations": len(cache), "params": params, "identifiability": ident, "storage_scheme": scheme}


def _file_scheme(replayer) -> dict:
    """The storage scheme keys at the house file's values (to undo a chosen scheme in a run)."""
    from ..declaration import load

    prm = load(replayer.plant_name).instances["storage"].params
    return {k: getattr(prm, k.split(".", 1)[1]) for _, sc in STORAGE_SCHEMES for k in sc}


def choose_storage_scheme(ctx, replayer, t_end: float) -> dict | None:
    """The STORAGE_SCHEMES entry with the lowest training cost (everything else at the replayer's
    base); it joins replayer.base. -> {chosen, overrides, train_cost {label: cost}} or None."""
    if "storage" not in replayer.instances() - replayer.calibrated:
        return None
    costs = {}
    for label, ov in STORAGE_SCHEMES:
        rows = replayer.run(ov, until=t_end)
        costs[label] = ctx.cost(rows[:, ctx.cols], ctx.train)
    label = min(costs, key=costs.get)
    chosen = dict(STORAGE_SCHEMES)[label]
    replayer.base = {**replayer.base, **chosen}
    return {"chosen": label, "overrides": chosen, "train_cost": costs}


# identifiability: a calibrated parameter is pinned down when its approximate 1-sigma interval
# (from the cost's curvature) spans less than this share of its physical range, and no pair of
# them trades off against each other (|correlation| above MAX_CORR)
MAX_SPAN = 0.5
MAX_CORR = 0.95


def identifiability(F, names, lo, hi, theta, n_eff: float, h: float = 0.05) -> dict:
    """Local identifiability of a calibration at its optimum theta: the Hessian of the cost F in
    range-normalised coordinates (u = (v - lo) / (hi - lo)) by central differences (steps h,
    kept inside the range), the approximate covariance 2 J / n_eff * H^-1 as for every fitted
    parameter here, each parameter's 1-sigma span as a share of its range and the correlations.
    -> {parameters: [{name, sigma_share_of_range, identifiable}], correlations: {"a|b": r},
    identifiable: bool, why}."""
    k = len(theta)
    # the curvature is taken a step inside the range when the optimum lies on a bound (the
    # differences must stay where the model is defined)
    u0 = np.clip([(v - a) / (b - a) for v, a, b in zip(theta, lo, hi)], h, 1.0 - h)
    steps = np.full(k, h)

    def G(u):
        return F([a + x * (b - a) for x, a, b in zip(u, lo, hi)])

    J = G(u0)
    H = np.zeros((k, k))
    for i in range(k):
        e = np.zeros(k)
        e[i] = steps[i]
        H[i, i] = (G(u0 + e) - 2.0 * J + G(u0 - e)) / steps[i] ** 2
        for j in range(i):
            f = np.zeros(k)
            f[j] = steps[j]
            H[i, j] = H[j, i] = (G(u0 + e + f) - G(u0 + e - f) - G(u0 - e + f) + G(u0 - e - f)) / (4 * steps[i] * steps[j])
    out = {"parameters": [], "correlations": {}, "identifiable": True, "why": ""}
    try:
        cov = np.linalg.inv(H) * 2.0 * J / max(n_eff, 1.0)
        ok = np.all(np.linalg.eigvalsh(H) > 0)
    except np.linalg.LinAlgError:
        cov, ok = np.full((k, k), np.inf), False
    why = []
    for i, name in enumerate(names):
        span = float(np.sqrt(cov[i, i])) if ok and cov[i, i] > 0 else math.inf
        ident = span <= MAX_SPAN
        out["parameters"].append({"name": name, "sigma_share_of_range": span if math.isfinite(span) else None,
                                  "identifiable": ident})
        if not ident:
            why.append(f"{name}: the cost hardly changes across its range (1-sigma span "
                       f"{'unbounded' if not math.isfinite(span) else f'{span:.2f} of it'})")
    for i in range(k):
        for j in range(i):
            if ok and cov[i, i] > 0 and cov[j, j] > 0:
                r = float(cov[i, j] / math.sqrt(cov[i, i] * cov[j, j]))
                out["correlations"][f"{names[j]}|{names[i]}"] = r
                if abs(r) > MAX_CORR:
                    why.append(f"{names[j]} and {names[i]} trade off (correlation {r:+.2f}): only a "
                               "combination of them is pinned down")
    out["identifiable"] = not why
    out["why"] = "; ".join(why)
    return out


@dataclass
class Result:
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

    def public(self) -> dict:
        return {"id": self.id, "component": self.component if self.signal is None else self.signal,
                "kind": self.kind, "plausible": self.plausible, "reason": self.reason,
                "parameters": {p.name: {"value": float(v), "stderr": float(s), "unit": p.unit,
                                        "nominal": p.nominal}
                               for p, v, s in zip(self.effect.params, self.theta, self.stderr)},
                "signal": self.signal, "train_cost": self.train_cost, "heldout_cost": self.held_cost,
                "heldout_gain": self.held_gain, "bic": self.bic, "accepted": self.accepted,
                "evaluations": self.evaluations, "nominal_refit": dict(self.nominal),
                "parameters_at_bound": list(self.at_bound), "relative_to_neighbours": self.local}


def _to_u(p, v):
    return math.log(v) if p.log else v


def _from_u(p, u):
    return min(max(math.exp(u) if p.log else u, p.lo), p.hi)


def _scalar_search(f, p, n_grid=6, maxiter=10):
    lo, hi = _to_u(p, p.lo), _to_u(p, p.hi)
    grid = np.linspace(lo, hi, n_grid)
    vals = [f(_from_u(p, u)) for u in grid]
    k = int(np.argmin(vals))
    a, b = grid[max(0, k - 1)], grid[min(n_grid - 1, k + 1)]
    res = minimize_scalar(lambda u: f(_from_u(p, u)), bounds=(a, b), method="bounded",
                          options={"xatol": (hi - lo) * 2e-3, "maxiter": maxiter})
    best_u, best_v = (res.x, res.fun) if res.fun <= vals[k] else (grid[k], vals[k])
    return _from_u(p, best_u), float(best_v), n_grid + int(res.nfev)


def _stderr(f, p, theta, J, n_eff):
    """Approximate standard error from the cost curvature: var = 2 J / (n_eff J'')."""
    h = 0.05 * (p.hi - p.lo) if not p.log else theta * 0.1
    lo, hi = max(p.lo, theta - h), min(p.hi, theta + h)
    if hi - lo <= 0:
        return math.nan
    Jl, Jh = f(lo), f(hi)
    # quadratic through three points
    x = np.array([lo, theta, hi])
    y = np.array([Jl, J, Jh])
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            c = np.polyfit(x - theta, y, 2)[0]
        except Exception:  # noqa: BLE001
            return math.nan
    if c <= 0:
        return math.nan
    return float(math.sqrt(2.0 * J / (n_eff * 2.0 * c)))


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
    t_end = float(ctx.rec.time[ctx.train].max())
    cache = {}
    own = set(effect.overrides([p.nominal for p in params]))
    nom = [q for q in (nominal or []) if q.name not in own] if JOINT_REFIT else []
    ne = len(params)

    scheme = {}  # the storage scheme chosen again with the candidate (STORAGE_SCHEMES), if another

    def ov(theta):
        d = {q.name: float(v) for q, v in zip(nom, theta[ne:])}
        d.update(scheme)
        d.update(effect.overrides(list(theta[:ne])))
        return d

    def F(theta):
        key = tuple(round(float(v), 12) for v in theta) + tuple(sorted(scheme.items()))
        if key not in cache:
            rows = replayer.run(ov(theta), until=t_end)
            cache[key] = ctx.cost(rows[:, ctx.cols], ctx.train)
        return cache[key]

    allp = list(params) + nom
    # the candidate is fitted with the nominals at their FILE values first (the baseline's
    # re-fit has already bent them towards the missing effect: starting there, the candidate
    # came out 16 % small on a 40 W/K storage loss and the joint pass stalled at 10x the cost)
    theta = [p.nominal for p in params] + [q.nominal for q in nom]
    J = math.nan

    def along(i):
        def f(v):
            th = list(theta)
            th[i] = v
            return F(th)
        return f

    def local_pass():
        nonlocal J
        for i in free:
            p = params[i]
            lo, hi = _to_u(p, p.lo), _to_u(p, p.hi)
            u = _to_u(p, theta[i])
            d = 0.15 * (hi - lo)
            f = along(i)
            res = minimize_scalar(lambda x: f(_from_u(p, x)), bounds=(max(lo, u - d), min(hi, u + d)),
                                  method="bounded", options={"xatol": (hi - lo) * 2e-3, "maxiter": 8})
            if res.fun < J:
                theta[i], J = _from_u(p, res.x), float(res.fun)

    for i in free:
        theta[i], J, _ = _scalar_search(along(i), params[i])
    if len(free) > 1:
        local_pass()
    if nom:
        th, Jn, _ = _descent(F, allp, theta, range(ne, ne + len(nom)), maxiter=5)
        if Jn < J:
            theta[:], J = th, Jn
            local_pass()
    if "storage" in replayer.instances() - replayer.calibrated:
        # a candidate acting on the storage (a port plume) trades off against how finely the
        # tank resolves its thermocline: the scheme is chosen again with the candidate fitted
        best = dict(scheme), J
        for _, sc in STORAGE_SCHEMES:
            scheme.clear()
            scheme.update(sc or _file_scheme(replayer))  # the file's: undo the nominal's choice
            Js = F(theta)
            if Js < best[1] - 1e-12:
                best = dict(scheme), Js
        scheme.clear()
        scheme.update(best[0])
        if best[1] < J:
            J = best[1]
            local_pass()
    n_eff = ctx.n_eff(ctx.train)
    se = [_stderr(along(i), params[i], theta[i], J, n_eff) if i in free else math.nan
          for i in range(len(params))]
    rows = replayer.run(ov(theta))
    sim = rows[:, ctx.cols]
    r = Result(effect.id, effect.component, effect.kind, True, theta=list(theta[:ne]), stderr=se,
               train_cost=ctx.cost(sim, ctx.train), held_cost=ctx.cost(sim, ctx.held),
               evaluations=len(cache) + 1, sim=sim, rows=rows, effect=effect,
               nominal={**{q.name: float(v) for q, v in zip(nom, theta[ne:])}, **scheme})
    r.k = len(free)
    return r


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


def fit_signal(effect, ctx, nominal_sim, replayer=None) -> Result:
    """Fit a post-processing candidate to each eligible signal; keep the one whose own residual
    it reduces by the largest share on training (a sensor effect explains its sensor's residual
    nearly whole; a structural difference it imitates, only in part). On a storage sensor the effect acts on the twin's
    value plus the neighbours' common residual (common_mode) and is judged there (Result.local);
    on the return of the radiator replayed alone (replayer given) it is fitted jointly with the
    radiator's rating and water content and judged on that return alone (Result.local)."""
    from ..catalogue import CATALOGUE
    from .cut import RADIATOR_OUTPUTS

    p = effect.params[0]
    t = ctx.rec.time
    best = None
    nfev = 0
    alone = set(RADIATOR_OUTPUTS) if replayer is not None and "radiator" in replayer.calibrated else set()
    for j, s in enumerate(ctx.measured):
        if CATALOGUE.signal(s).unit not in effect.signal_units:
            continue
        c = common_mode(ctx, nominal_sim, j)
        y0 = nominal_sim[:, j] + (c if c is not None else 0.0)
        m = ctx.train & ctx.ok[:, j]
        if m.sum() < 10:
            continue

        def fit_on(y0, m=m, j=j):
            def f(v):
                return float(np.mean((ctx.meas[m, j] - effect.apply(t, y0, [v])[m]) ** 2))
            if effect.id == "sensor_offset":
                v = float(np.clip(np.mean(ctx.meas[m, j] - y0[m]), p.lo, p.hi))
                return v, f(v), 1, f
            return _scalar_search(f, p, n_grid=5, maxiter=8) + (f,)

        y_before = y0
        v, J, k, f = fit_on(y0)
        nfev += k
        if s in alone:
            # the radiator replayed alone: its rating, water content and element count are
            # re-fitted with the candidate applied (a larger radiator delays its return too:
            # calibrated without the candidate it absorbs part of a sensor's delay), two alternations
            for _ in range(2):
                vals, N = replayer.refit_radiator(lambda y, v=v: effect.apply(t[:len(y)], y, [v]), ctx.train)
                y0 = replayer.radiator_return(vals, N)
                v, J, k, f = fit_on(y0)
                nfev += k
        J0 = float(np.mean((ctx.meas[m, j] - y_before[m]) ** 2))
        red = (J0 - J) / max(J0, 1e-12)  # the share of the signal's own residual the effect removes
        # a storage sensor's share is of its residual relative to its neighbours, the return of a
        # subsystem replayed alone of its residual there, another signal's of its whole residual
        # (a structural bias included): a local one whose share would pass LOCAL_GAIN goes first
        local = c is not None or s in alone
        key = (local and red >= LOCAL_GAIN, red)
        if best is None or key > best[0]:
            best = (key, j, v, f, y0, local, y_before)
    if best is None:
        return Result(effect.id, effect.component, effect.kind, False, "no eligible measured signal",
                      effect=effect)
    _, j, v, f, y0, local, y_before = best
    sim = nominal_sim.copy()
    sim[:, j] = effect.apply(t, y0, [v])
    m = ctx.train & ctx.ok[:, j]
    se = _stderr(f, p, v, f(v), ctx.n_eff(ctx.train)) if effect.id != "sensor_offset" else \
        float(np.std(ctx.meas[m, j] - sim[m, j]) / math.sqrt(ctx.n_eff(ctx.train)))
    r = Result(effect.id, "sensor", effect.kind, True, theta=[v], stderr=[se], signal=ctx.measured[j],
               train_cost=ctx.cost(sim, ctx.train), held_cost=ctx.cost(sim, ctx.held),
               evaluations=nfev, sim=sim, effect=effect)
    if local:
        h = ctx.held & ctx.ok[:, j]
        e0, e1 = ctx.meas[h, j] - y_before[h], ctx.meas[h, j] - sim[h, j]
        r.local = {"heldout_rms_before": float(np.sqrt(np.mean(e0 ** 2))),
                   "heldout_rms_after": float(np.sqrt(np.mean(e1 ** 2))),
                   "gain": 1.0 - float(np.mean(e1 ** 2)) / max(float(np.mean(e0 ** 2)), 1e-12),
                   "limit": 0.3 * ctx.scale[j] + 3.0 * ctx.noise[j],
                   "neighbours": [ctx.measured[k] for k in neighbours(ctx, j)]}
        if ctx.measured[j] in alone:
            # calibrated on this very signal, the subsystem alone has no structural allowance to
            # keep: its residual is a mismatch above the sensor's noise (3 sigma)
            r.local["what"] = f"{ctx.measured[j]} (radiator replayed alone, re-fitted with the candidate)"
            r.local["limit"] = 3.0 * ctx.noise[j]
    return r
