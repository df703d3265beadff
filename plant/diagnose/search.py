"""Data-driven search for a residual term the catalogue lacks.

For the signals that carry the mismatch, the residual (measured - simulated) and its time
derivative (a state error grows with the integral of a missing heat flow) are regressed on
physically meaningful features by forward stepwise least squares: operating-mode indicators,
flows, temperature differences and their products with the modes. Fitted on the training window,
scored on the held-out window (R2); the top terms are reported with their coefficients.
"""
from __future__ import annotations

import numpy as np



# the terms are written for house 1's plant (a CHP and a boiler on a switch, a mixing station):
# the signals and modes they read
NEEDS = ("storage.T_sensor_1", "storage.T_sensor_10", "mixer.m_flow_primary", "boiler.m_flow", "chp.m_flow",
         "switch.T_sup", "switch.T_ret", "weather.T_air")
NEEDS_MODES = ("chp_on", "chp_off", "boiler_on", "heating_on", "dhw_on", "chp_off_heating_on")


def applies(ctx) -> bool:
    """Whether the replayed house has what the terms read."""
    return all(n in ctx.roles.catalogue for n in NEEDS) and all(m in ctx.flags for m in NEEDS_MODES)


def features(ctx, rows: np.ndarray) -> dict[str, np.ndarray]:
    g = lambda n: rows[:, ctx.index(n)]  # noqa: E731
    f = ctx.flags
    n = len(rows)
    on = {k: v[:n].astype(float) for k, v in f.items()}
    T_top, T_bot = g("storage.T_sensor_10"), g("storage.T_sensor_1")
    T_mean = np.mean([g(f"storage.T_sensor_{i}") for i in range(1, 11)], axis=0)
    m_prim, m_b, m_c = g("mixer.m_flow_primary"), g("boiler.m_flow"), g("chp.m_flow")
    T_sh, T_rh = g("switch.T_sup"), g("switch.T_ret")
    dt_sim = np.gradient(rows[:, ctx.cols], ctx.rec.time[:n], axis=0)
    feats = {
        "1 (constant)": np.ones(n),
        "[CHP on]": on["chp_on"],
        "[boiler on]": on["boiler_on"],
        "[heating pump on]": on["heating_on"],
        "[DHW charging on]": on["dhw_on"],
        "[CHP off & heating on]": on["chp_off_heating_on"],
        "[CHP off] x heating primary flow": on["chp_off"] * m_prim,
        "[CHP off] x heating primary flow x (T_sup_header - T_ret_header)": on["chp_off"] * m_prim * (T_sh - T_rh),
        "[CHP off] x boiler flow": on["chp_off"] * m_b,
        "CHP flow x (T_sup_header - T_ret_header)": m_c * (T_sh - T_rh),
        "storage mean - 18 degC (loss to room)": T_mean - 18.0,
        "storage top - bottom (stratification)": T_top - T_bot,
        "supply header - 18 degC": T_sh - 18.0,
        "outdoor air temperature": g("weather.T_air"),
        "heating primary flow": m_prim,
        "boiler flow": m_b,
    }
    feats["_dsim"] = dt_sim
    return feats


def _stepwise(X: dict, y: np.ndarray, train: np.ndarray, held: np.ndarray, k: int = 3):
    names = [n for n in X if not n.startswith("_")]
    chosen: list[str] = []
    ok = np.isfinite(y)
    tr, he = train & ok, held & ok
    if tr.sum() < 20 or he.sum() < 20:
        return [], 0.0
    var_he = float(np.var(y[he])) or 1e-12
    best_r2 = 0.0
    terms = []
    for _ in range(k):
        cand = None
        for nm in names:
            if nm in chosen:
                continue
            cols = chosen + [nm]
            A = np.column_stack([X[c] for c in cols])
            coef, *_ = np.linalg.lstsq(A[tr], y[tr], rcond=None)
            r2 = 1.0 - float(np.mean((y[he] - A[he] @ coef) ** 2)) / var_he
            if cand is None or r2 > cand[0]:
                cand = (r2, nm, coef)
        if cand is None or cand[0] - best_r2 < 0.02:
            break
        best_r2 = cand[0]
        chosen.append(cand[1])
        terms = [{"term": c, "coefficient": float(v)} for c, v in zip(chosen, cand[2])]
        for i, t in enumerate(terms):
            t["heldout_r2_after_adding"] = None
        terms[-1]["heldout_r2_after_adding"] = best_r2
    return terms, best_r2


def search(ctx, rows: np.ndarray, signals: list[str], top: int = 3) -> list[dict]:
    """Top residual terms per mismatched signal (level and rate form); none where the house lacks
    what the terms read (applies)."""
    if not applies(ctx):
        return []
    X = features(ctx, rows)
    out = []
    for s in signals[:4]:
        j = ctx.measured.index(s)
        r = ctx.residual(rows[:, ctx.cols])[:, j]
        t = ctx.rec.time[: len(r)]
        terms, r2 = _stepwise(X, r, ctx.train[: len(r)], ctx.held[: len(r)], top)
        X2 = dict(X)
        X2["d(simulated)/dt (lag/delay)"] = X["_dsim"][:, j]
        rr = np.where(np.isfinite(r), r, 0.0)
        dr = np.gradient(rr, t)
        terms_d, r2_d = _stepwise({k: v for k, v in X2.items() if k != "1 (constant)"}, dr,
                                  ctx.train[: len(r)], ctx.held[: len(r)], top)
        form, tt, rr2 = ("level", terms, r2) if r2 >= r2_d else ("rate d(residual)/dt", terms_d, r2_d)
        out.append({"signal": s, "form": form, "terms": tt, "heldout_r2": rr2})
    return out
