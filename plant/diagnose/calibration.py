"""Calibrate the nominal structure the recording can pin down, before and beside the candidates.

Nominal re-fit (knobs: the kinds' KNOBS): a few nominal twin parameters that are uncertain in the house
file but matter for replay are re-fitted within bounds on the training window (narrow, +-10 % of
the file value, or a rig's declared tolerance: the storage loss +-40 %, the DHW coil +-25 %, the
CHP's water and metal 2.5-30 l), (1) for the nominal model alone, so the "before" baseline is the best nominal
twin (refit_nominal), and (2) jointly with each simulate-kind candidate's own parameters (one
bounded Brent pass over them after the candidate's fit, then a local pass over the candidate's
parameters again). The narrow bounds keep them from soaking up a missing effect. They count for
the nominal model and every candidate alike, so they cancel in the BIC comparison. A candidate
that fits one of them itself (heat_loss: storage.UA_loss) keeps its own, wide-range, value.

Also here: the storage scheme (STORAGE_SCHEMES, a discrete structural choice made before the
re-fit) and the identifiability check of a calibration (identifiability).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .bounded import at_bound, descent
from .effects.base import Param


@dataclass(frozen=True)
class NominalParam:
    key: str          # house-file override "section.key"
    rel: float        # bounds: file value * (1 -+ rel)
    unit: str
    why: str
    bounds: tuple | None = None  # absolute bounds instead (a file value of 0: the ideal)
    joint: bool = True           # re-fitted again with each simulate candidate (fit.JOINT_REFIT)
    signals: tuple = ()          # calibrated first, on these signals alone (a part with its own sensors)

    def overrides(self, value: float) -> dict:
        return {self.key: float(value)}


def knobs(house: str) -> tuple:
    """The house's re-fitted nominals (NominalParam), from its kinds' KNOBS (plant/component.py
    Knob): each instance's, named for it and its links, in the order of the knobs' rank (the
    slow whole-tank parts first) and then of declaration; a key two instances name (a storage two
    coupling points feed) once."""
    from ..declaration import load
    from ..kinds import KINDS

    spec = load(house)
    found = {}
    for n, inst in enumerate(spec.instances.values()):
        for k in KINDS[inst.kind].KNOBS:
            key = _named(inst, k.key)
            if key in found:
                continue
            q = NominalParam(key, k.rel, k.unit, k.why, k.bounds, k.joint,
                             tuple(s for local in k.signals for s in _outputs(spec, inst, local)))
            found[key] = (k.rank, n, q)
    return tuple(q for _, _, q in sorted(found.values(), key=lambda v: v[:2]))


def _named(inst, local: str) -> str:
    """A knob's key for `inst`: its own parameter, or `link.name` on the instance the link names."""
    link, _, name = local.rpartition(".")
    return f"{inst.options[link]}.{name}" if link else f"{inst.name}.{name}"


def _outputs(spec, inst, local: str) -> list:
    """A knob's signals: the instance's own output, or `link.*`: the sensors of the storage the
    link names."""
    if not local.endswith(".*"):
        return [f"{inst.name}.{local}"]
    st = spec.instances[inst.options[local[:-2]]]
    n = st.options.get("sensors", 10)
    return [f"{st.name}.T_sensor_{k}" for k in range(1, (n if isinstance(n, int) else 10) + 1)]


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
# (storage_mixing), fitted with the scheme chosen again jointly (fit.fit_simulate).
STORAGE_SCHEMES = (
    ("file (superbee, 40 layers)", {}),
    ("upwind, 20 layers", {"storage.limiter": 0, "storage.n_layers": 20}),
    ("upwind, 30 layers", {"storage.limiter": 0, "storage.n_layers": 30}),
    ("upwind, 50 layers", {"storage.limiter": 0, "storage.n_layers": 50}),
    ("upwind, 80 layers", {"storage.limiter": 0, "storage.n_layers": 80}),
)


def nominal_params(house: str, refit=None, instances=None) -> list:
    """Param objects (name = override key, bounds = file value -+ rel) of the re-fitted nominals
    (instances: those the replay has, Replayer.instances(); a cut replaces the radiator and the
    room by measurements, so their parameters are not re-fitted there)."""
    from ..declaration import load

    spec = load(house)
    out = []
    for q in refit if refit is not None else knobs(house):
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


def refit_nominal(ctx, replayer, house: str, refit=None, jobs: int | None = 1) -> dict:
    """Fit the nominal re-fit parameters of the nominal model (no candidate) on the training
    window. -> report entry; its "overrides" (the fitted values and the storage scheme chosen)
    are what every later replay starts from (Replayer.with_calibration), its "params" those
    re-fitted again with each candidate."""
    refit = knobs(house) if refit is None else refit
    params = nominal_params(house, refit, replayer.instances() - replayer.calibrated)
    refit = [q for q in refit if q.key in {p.name for p in params}]

    def overrides(theta):
        return {k: v for q, x in zip(refit, theta) for k, v in q.overrides(x).items()}

    t_end = float(ctx.rec.time[ctx.train].max())
    scheme = choose_storage_scheme(ctx, replayer, t_end)
    rp = replayer.with_calibration(scheme_overrides(scheme, replayer)) if scheme else replayer
    if not params:
        return {"parameters": [], "train_cost_file": math.nan, "train_cost_refit": math.nan,
                "storage_scheme": scheme, "overrides": _added(replayer, rp)}
    cache = {}

    def F(theta, signals=()):
        key = tuple(round(float(v), 9) for v in theta) + tuple(signals)
        if key not in cache:
            rows = rp.run(overrides(theta), until=t_end).rows
            cache[key] = ctx.cost(rows[:, ctx.cols], ctx.train, signals=signals)
        return cache[key]

    theta0 = [p.nominal for p in params]
    J_file = F(theta0)
    theta = list(theta0)
    # parts with their own sensors first, on those sensors alone (two passes: the pair trades off)
    for signals in dict.fromkeys(q.signals for q in refit if q.signals):
        if any(s in ctx.measured for s in signals):
            idx = [i for i, q in enumerate(refit) if q.signals == signals]
            for _ in range(2):
                theta, _, _ = descent(lambda th: F(th, signals), params, theta, idx)
    rest = [i for i, q in enumerate(refit) if not q.signals]
    theta, J, _ = descent(F, params, theta, rest)
    rp = rp.with_calibration(overrides(theta))
    if scheme is not None:
        # chosen again with the re-fitted values, as each simulate candidate chooses it after its
        # own fit: else a candidate gains by the second choice alone (labsim's 3-day no-effect
        # case: 30 layers before the re-fit, 80 after; every candidate gained 27-36 % with its
        # own parameter at nominal, and storage_mixing was named)
        again = choose_storage_scheme(ctx, rp, t_end)
        rp = rp.with_calibration(scheme_overrides(again, rp))
        if again["chosen"] != scheme["chosen"]:
            cache.clear()
            theta, J, _ = descent(F, params, theta, rest)
            rp = rp.with_calibration(overrides(theta))
            again["before_the_refit"] = scheme["chosen"]
        scheme = again
    rows = []
    for p, q, v in zip(params, refit, theta):
        rows.append({"name": p.name, "file_value": p.nominal, "fitted_value": float(v),
                     "change_pct": 100.0 * (v / p.nominal - 1.0) if p.nominal else math.nan,
                     "bounds": [p.lo, p.hi], "unit": p.unit,
                     "at_bound": at_bound(p, v) and not (q.bounds is not None and v == p.nominal), "why": q.why})
    evaluations = len(cache)  # the re-fit's own; the identifiability's are counted in its entry

    def R(theta):  # the residuals whose sum of squares is F(theta)
        return ctx.weighted_residuals(rp.run(overrides(theta), until=t_end).rows[:, ctx.cols], ctx.train)
    ident = identifiability(R, [p.name for p in params], [p.lo for p in params], [p.hi for p in params],
                            theta, ctx.n_eff(ctx.train), jobs=jobs)
    return {"parameters": rows, "train_cost_file": J_file, "train_cost_refit": J,
            "evaluations": evaluations, "params": [p for p, q in zip(params, refit) if q.joint],
            "identifiability": ident, "storage_scheme": scheme, "overrides": _added(replayer, rp)}


def _added(before, after) -> dict:
    """The base overrides `after` holds that `before` does not (or holds with another value)."""
    return {k: v for k, v in after.base.items() if k not in before.base or before.base[k] != v}


def ranges(nref) -> dict:
    """override key -> (lo, hi): the values the nominal re-fit could take, from refit_nominal's
    report entry."""
    return {row["name"]: (float(row["bounds"][0]), float(row["bounds"][1])) for row in nref.get("parameters", [])}


def file_scheme(replayer) -> dict:
    """The storage scheme keys at the house file's values (to undo a chosen scheme in a run)."""
    from ..declaration import load

    prm = load(replayer.plant_name).instances["storage"].params
    return {k: getattr(prm, k.split(".", 1)[1]) for _, sc in STORAGE_SCHEMES for k in sc}


def choose_storage_scheme(ctx, replayer, t_end: float) -> dict | None:
    """The STORAGE_SCHEMES entry with the lowest training cost (everything else at the replayer's
    base). -> {chosen, overrides (None: the file's), train_cost {label: cost}} or None when the
    storage is not replayed; scheme_overrides gives what it sets."""
    if "storage" not in replayer.instances() - replayer.calibrated:
        return None
    costs = {}
    for label, ov in STORAGE_SCHEMES:
        rows = replayer.run(ov or file_scheme(replayer), until=t_end).rows  # the file's: undo an earlier choice
        costs[label] = ctx.cost(rows[:, ctx.cols], ctx.train)
    label = min(costs, key=costs.get)
    chosen = dict(STORAGE_SCHEMES)[label]
    return {"chosen": label, "overrides": chosen, "train_cost": costs}


def scheme_overrides(scheme: dict, replayer) -> dict:
    """What a chosen storage scheme sets (the file's own values for the file's scheme)."""
    return scheme["overrides"] or file_scheme(replayer)


# identifiability: a calibrated parameter is pinned down when its approximate 1-sigma interval
# (from the cost's curvature) spans less than this share of its physical range, and no pair of
# them trades off against each other (|correlation| above MAX_CORR)
MAX_SPAN = 0.5
MAX_CORR = 0.95


def identifiability(R, names, lo, hi, theta, n_eff: float, h: float = 0.05, jobs: int | None = 1) -> dict:
    """Local identifiability of a calibration at its optimum theta. R(values) is the
    calibration's weighted residual vector, its cost R.R. The cost's Hessian in range-normalised
    coordinates (u = (v - lo) / (hi - lo)) is taken as Gauss-Newton's 2 J'J, J the residuals'
    Jacobian by forward differences (steps h, kept inside the range), and the approximate
    covariance as 2 cost / n_eff * H^-1 as for every fitted parameter here; from it each
    parameter's 1-sigma span as a share of its range and the correlations. 1 + k independent
    replays in up to `jobs` processes (parallel.map_forked): the cost's own Hessian by
    differences took 1 + 2k + k(k-1)/2: 45 with house 1's eight re-fitted parameters, 9 here.
    -> {parameters: [{name, sigma_share_of_range, identifiable}], correlations: {"a|b": r},
    identifiable: bool, why, evaluations}."""
    from .parallel import map_forked

    k = len(theta)
    # the Jacobian is taken a step inside the range when the optimum lies on a bound (the
    # differences must stay where the model is defined)
    u0 = np.clip([(v - a) / (b - a) for v, a, b in zip(theta, lo, hi)], 0.0, 1.0 - h)
    points = [u0] + [u0 + h * np.eye(k)[i] for i in range(k)]
    values = map_forked(lambda n: np.asarray(R([a + x * (b - a) for x, a, b in zip(points[n], lo, hi)]), float),
                        len(points), jobs)
    r0 = np.nan_to_num(values[0])
    Jac = np.stack([(np.nan_to_num(v) - r0) / h for v in values[1:]], axis=1)
    J = float(r0 @ r0)
    H = 2.0 * Jac.T @ Jac
    out = {"parameters": [], "correlations": {}, "identifiable": True, "why": "", "evaluations": len(points)}
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
