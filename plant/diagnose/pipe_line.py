"""Diagnose a measured pipe: replay the declared pipe, fit the effects the literature names, keep what holds.

    from plant.diagnose.pipe_line import diagnose_pipe, format_report
    report = diagnose_pipe("profiles/recordings/pipes/ULg151202")
    print(format_report(report))

Method
------
1. Replay the declared pipe (the plain pipe kind of plant/grid/pipe.py, pipe.toml's data) on the
   measured inlet temperature and flow(s) (pipe_recording.py) and compare the outlet temperature.
2. Split the scored samples into alternating blocks, training and held-out (`split`): a block is a
   quarter of the path's transport delay at its median flow, so every front that passes the outlet
   (it takes about the delay, less for the rise itself) lands in both parts, but at least
   MIN_BLOCK samples, so that a held-out block is more than the neighbours of training samples.
   Samples before the path's water has been replaced once are not scored when the declaration
   gives no initial temperature (the initial state is unknown until then).
3. Fit each candidate effect the literature names (CANDIDATES; bounded 1-D fits, scipy) on the
   training part; keep the one with the lowest BIC on the training part among those that lower the
   BIC by at least DBIC_MIN and cut the held-out RMSE by at least HELD_CUT; then, with it in place,
   try each other candidate jointly (2-D) by the same rule, up to MAX_EFFECTS.
4. Report the held-out RMSE of the plain and the diagnosed pipe, each effect named with its fitted
   value against the pipe's published data, and the published Modelica PlugFlowPipe's RMSE on the
   same held-out window where its result is shipped (modelica_reference.csv).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize, minimize_scalar

from ..grid.pipe import taylor_dispersion
from . import pipe_recording as pr

MIN_BLOCK = 6        # samples per split block at least (see the method above)
DBIC_MIN = 10.0      # BIC drop to accept an effect: "very strong" evidence (Kass and Raftery 1995)
HELD_CUT = 0.10      # held-out RMSE cut to accept one: less is within what a nuisance re-fit gives
MAX_EFFECTS = 2      # a pipe test is one step at one flow: its rise, delay and level fix few parameters
GRID = 7             # coarse grid points before the bounded Brent fit (guards against a side minimum)
TIE_BIC = 2.0        # BIC apart by less: the data cannot tell them apart ("not worth more than a bare
                     # mention", Kass and Raftery 1995); the tie goes to the effect whose fitted size the
PUBLISHED_FACTOR = 2.0   # pipe's published data predict within this factor (e.g. an outlet-lumped wall and
                     # a sensor lag are the same first-order lag at one constant flow)
AT_BOUND = 0.01      # a fit within this share of its range from a bound is not accepted: it compensates
                     # something else rather than measuring an effect of plausible size


@dataclass(frozen=True)
class Candidate:
    name: str
    option: str          # field of pipe_recording.Options
    unit: str
    source: str          # where the literature names it

    def bounds(self, rec) -> tuple[float, float]:
        C = sum(s.C_steel for s in rec.segments) or 1e5
        return {"C_wall": (0.0, 5.0 * C), "U_factor": (0.2, 5.0), "dispersion": (0.0, 0.5),
                "sensor_tau": (0.0, 120.0), "flow_factor": (0.8, 1.25), "T_env_offset": (-15.0, 15.0)}[self.option]

    def published(self, rec) -> tuple[float | None, str]:
        if self.option == "C_wall":
            C = sum(s.C_steel for s in rec.segments)
            return (C, "the steel wall's mass x cp (pipe.toml)") if C else (None, "no wall data")
        if self.option == "dispersion":
            last = rec.segments[-1]
            f = np.abs(rec.flow(last))
            return taylor_dispersion(last.diameter, float(np.median(f[f > 0]))), "Taylor (1954) at the median flow"
        if self.option == "T_env_offset":
            return 0.0, "the declared surroundings"
        return ({"U_factor": 1.0, "flow_factor": 1.0}.get(self.option),
                {"U_factor": "x the declared U", "flow_factor": "the meter as read",
                 "sensor_tau": "no published value"}[self.option])


CANDIDATES = (
    Candidate("wall_capacity", "C_wall", "J/K", "van der Heijde et al. 2017 (ULg validation), Modelica "
              "PlugFlowPipe: the wall's heat capacity lumped at the outlet"),
    Candidate("heat_loss", "U_factor", "1", "a loss coefficient other than the insulation's (PipeDataULg: "
              "'the insulation is quite aged'); van der Heijde et al. 2017"),
    Candidate("dispersion", "dispersion", "m2/s", "axial dispersion of a front in turbulent flow (Taylor 1954)"),
    Candidate("sensor_lag", "sensor_tau", "s", "the outlet sensor's own first-order lag"),
    Candidate("flow_meter", "flow_factor", "1", "the flow within its measurement uncertainty (PlugFlowULg.mo's gain)"),
    Candidate("ambient", "T_env_offset", "K", "surroundings other than declared (PlugFlowULg.mo: 22 degC vs 18 degC)"),
)


def scored(rec) -> np.ndarray:
    """Samples to score: outlet measured and, without a declared initial state, the path flushed once."""
    ok = np.isfinite(rec.T_out)
    if rec.T_init is None:
        t_flushed = rec.time[0]
        for seg in rec.segments:
            f = np.abs(rec.flow(seg))
            cum = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(rec.time))])
            i = int(np.searchsorted(cum, seg.mass))
            t_flushed = max(t_flushed, rec.time[min(i, len(rec.time) - 1)])
        ok &= rec.time >= t_flushed
    return ok


def split(rec) -> tuple[np.ndarray, np.ndarray, float]:
    """(training mask, held-out mask, block length [s]): alternating blocks, training first."""
    dt = float(np.median(np.diff(rec.time)))
    block = max(rec.delay() / 4.0, MIN_BLOCK * dt)
    odd = (np.floor((rec.time - rec.time[0]) / block).astype(int) % 2) == 1
    ok = scored(rec)
    return ok & ~odd, ok & odd, block


def rmse(y, T, mask) -> float:
    return float(np.sqrt(np.mean((y[mask] - T[mask]) ** 2)))


def bic(y, T, mask, k: int) -> float:
    n = int(mask.sum())
    sse = float(np.sum((y[mask] - T[mask]) ** 2))
    return n * math.log(max(sse, 1e-12) / n) + k * math.log(n)


def _fit1(rec, base: pr.Options, cand: Candidate, train) -> tuple[float, np.ndarray]:
    """Bounded 1-D fit of one candidate on the training samples: coarse grid, then Brent."""
    lo, hi = cand.bounds(rec)

    def cost(x):
        y = pr.replay(rec, replace(base, **{cand.option: float(x)}))
        return float(np.sum((y[train] - rec.T_out[train]) ** 2))

    xs = np.linspace(lo, hi, GRID)
    costs = [cost(x) for x in xs]
    i = int(np.argmin(costs))
    a, b = xs[max(i - 1, 0)], xs[min(i + 1, GRID - 1)]
    r = minimize_scalar(cost, bounds=(a, b), method="bounded", options={"xatol": 1e-4 * (hi - lo)})
    x = float(r.x) if r.fun <= costs[i] else float(xs[i])
    return x, pr.replay(rec, replace(base, **{cand.option: x}))


def _fitn(rec, base: pr.Options, cands: list, train) -> tuple[pr.Options, np.ndarray]:
    """Joint bounded fit (Powell) of several candidates, from base's values; each scaled to its bounds."""
    bounds = [c.bounds(rec) for c in cands]
    x0 = [(getattr(base, c.option) - lo) / (hi - lo) for c, (lo, hi) in zip(cands, bounds)]

    def opts(u):
        return replace(base, **{c.option: lo + float(np.clip(v, 0, 1)) * (hi - lo)
                                for c, v, (lo, hi) in zip(cands, u, bounds)})

    def cost(u):
        y = pr.replay(rec, opts(u))
        return float(np.sum((y[train] - rec.T_out[train]) ** 2))

    r = minimize(cost, x0, method="Powell", bounds=[(0.0, 1.0)] * len(cands),
                 options={"xtol": 1e-3, "ftol": 1e-6, "maxfev": 60 * len(cands)})
    o = opts(r.x)
    return o, pr.replay(rec, o)


def _row(rec, cand, o, y, train, held, k) -> dict:
    value = getattr(o, cand.option)
    pub, label = cand.published(rec)
    return {"effect": cand.name, "value": value, "unit": cand.unit, "published": pub, "published_is": label,
            "ratio": value / pub if pub else None, "bic": bic(y, rec.T_out, train, k),
            "rmse_train": rmse(y, rec.T_out, train), "rmse_held": rmse(y, rec.T_out, held), "source": cand.source,
            "at_bound": min(abs(value - b) for b in cand.bounds(rec)) <= AT_BOUND * (cand.bounds(rec)[1] - cand.bounds(rec)[0])}


def _round(rec, chosen: list, base: pr.Options, train, held) -> list:
    """Fit each candidate not yet chosen with the chosen ones in place; rows sorted by BIC."""
    rows = []
    for cand in CANDIDATES:
        if cand in chosen:
            continue
        if chosen:
            o, y = _fitn(rec, base, chosen + [cand], train)
        else:
            x, y = _fit1(rec, base, cand, train)
            o = replace(base, **{cand.option: x})
        row = _row(rec, cand, o, y, train, held, len(chosen) + 1)
        rows.append((row, cand, o, y))
    return sorted(rows, key=lambda r: r[0]["bic"])


def _reference(rec, y_plain, y_diag, held) -> dict | None:
    """RMSE of the published Modelica pipe and of ours at its points inside the held-out blocks."""
    if rec.reference is None:
        return None
    t, T = rec.reference
    i = np.clip(np.searchsorted(rec.time, t), 0, len(rec.time) - 1)
    inside = held[i] & held[np.maximum(i - 1, 0)] & (t <= rec.time[-1])
    if rec.T_init is None:
        inside &= t >= 10000.0       # PlugFlowAIT.mo: not initialised, ignore the first 10,000 s
    if inside.sum() < 3:
        return None
    meas = np.interp(t[inside], rec.time, rec.T_out)

    def err(v):
        return float(np.sqrt(np.mean((v - meas) ** 2)))
    return {"points": int(inside.sum()), "rmse_modelica": err(T[inside]),
            "rmse_plain": err(np.interp(t[inside], rec.time, y_plain)),
            "rmse_diagnosed": err(np.interp(t[inside], rec.time, y_diag))}


def _tie_break(ok: list):
    """The lowest-BIC row, unless rows within TIE_BIC of it include one whose fitted size its published
    value predicts (within PUBLISHED_FACTOR) while the best's does not: that one."""
    tied = [r for r in ok if r[0]["bic"] < ok[0][0]["bic"] + TIE_BIC]

    def predicted(r):
        q = r[0]["ratio"]
        return q is not None and 1.0 / PUBLISHED_FACTOR <= q <= PUBLISHED_FACTOR and r[0]["published"] not in (0.0, 1.0)
    pick = next((r for r in tied if predicted(r)), ok[0])
    pick[0]["tied_with"] = [f"{r[0]['effect']} {_value(r[0]['value'], r[0]['unit'])} (dBIC {r[0]['bic'] - pick[0]['bic']:+.1f})"
                            for r in tied if r is not pick]
    return pick


def diagnose_pipe(path, log=None) -> dict:
    """The diagnosis of one pipe recording (see the module's method)."""
    rec = pr.load(path)
    train, held, block = split(rec)
    base = pr.Options()
    y0 = pr.replay(rec, base)
    cur = {"bic": bic(y0, rec.T_out, train, 0), "rmse_held": rmse(y0, rec.T_out, held)}
    plain = dict(cur, rmse_train=rmse(y0, rec.T_out, train))
    chosen, effects, rounds, y, tied = [], [], [], y0, {}
    while len(chosen) < MAX_EFFECTS:
        rows = _round(rec, chosen, base, train, held)
        rounds.append([r[0] for r in rows])
        ok = [r for r in rows if r[0]["bic"] <= cur["bic"] - DBIC_MIN and not r[0]["at_bound"]
              and r[0]["rmse_held"] <= (1.0 - HELD_CUT) * cur["rmse_held"]]
        if log:
            log(f"round {len(rounds)}: " + ", ".join(f"{r[0]['effect']} dBIC {r[0]['bic'] - cur['bic']:+.0f} "
                                                     f"held {r[0]['rmse_held']:.3f} K" for r in rows))
        if not ok:
            break
        row, cand, base, y = _tie_break(ok)
        chosen.append(cand)
        tied[cand.name] = row.get("tied_with", [])
        cur = row
        effects = [dict(_row(rec, c, base, y, train, held, len(chosen)), tied_with=tied[c.name]) for c in chosen]
    return {"recording": str(rec.source), "samples": len(rec.time), "train": int(train.sum()),
            "held_out": int(held.sum()), "block_s": block, "delay_s": rec.delay(),
            "rmse_plain": plain["rmse_held"], "rmse_plain_train": plain["rmse_train"],
            "rmse_diagnosed": cur["rmse_held"], "effects": effects, "rounds": rounds,
            "reference": _reference(rec, y0, y, held), "outlet_plain": y0, "outlet_diagnosed": y,
            "time": rec.time, "measured": rec.T_out, "warnings": rec.warnings}


def _value(v, unit) -> str:
    if unit == "J/K":
        return f"{v / 1000:.1f} kJ/K"
    if unit == "m2/s":
        return f"{v:.2g} m2/s"
    return f"{v:.3g} {unit}" if unit != "1" else f"{v:.3f}"


def format_report(r: dict) -> str:
    """The report as text: split, per-candidate fits, the named effects, RMSEs and the reference."""
    lines = [f"pipe recording {r['recording']}: {r['samples']} samples, transport delay {r['delay_s']:.0f} s",
             f"split: alternating blocks of {r['block_s']:.0f} s: {r['train']} training, {r['held_out']} held-out samples",
             f"plain pipe: outlet RMSE {r['rmse_plain_train']:.3f} K training, {r['rmse_plain']:.3f} K held-out"]
    for i, rows in enumerate(r["rounds"], 1):
        lines.append(f"candidates, round {i} (fitted on the training part):")
        for row in rows:
            lines.append(f"  {row['effect']:14s} {_value(row['value'], row['unit']):>14s}  BIC {row['bic']:9.1f}  "
                         f"RMSE train {row['rmse_train']:.3f} K, held-out {row['rmse_held']:.3f} K"
                         + ("  (at its bound: not accepted)" if row["at_bound"] else ""))
    if not r["effects"]:
        lines.append(f"no effect passes (BIC drop >= {DBIC_MIN:g} and held-out cut >= {HELD_CUT:.0%}): the declared pipe stands")
    for e in r["effects"]:
        pub = (f"; published {_value(e['published'], e['unit'])} ({e['published_is']})"
               + (f", ratio {e['ratio']:.2f}" if e["ratio"] is not None else "")) if e["published"] is not None \
            else f"; {e['published_is']}"
        lines.append(f"EFFECT {e['effect']} = {_value(e['value'], e['unit'])}{pub}  [{e['source']}]")
        if e.get("tied_with"):
            lines.append(f"  fits as well: {', '.join(e['tied_with'])}; the tie goes to the effect the published "
                         f"data predict (within a factor {PUBLISHED_FACTOR:g})")
    cut = 1.0 - r["rmse_diagnosed"] / r["rmse_plain"] if r["rmse_plain"] > 0 else 0.0
    lines.append(f"held-out outlet RMSE: plain {r['rmse_plain']:.3f} K, diagnosed {r['rmse_diagnosed']:.3f} K ({cut:+.0%} cut)")
    ref = r["reference"]
    if ref:
        lines.append(f"Modelica PlugFlowPipe (published result), {ref['points']} points in the held-out blocks: RMSE "
                     f"{ref['rmse_modelica']:.3f} K; at the same points plain {ref['rmse_plain']:.3f} K, "
                     f"diagnosed {ref['rmse_diagnosed']:.3f} K")
    return "\n".join(lines + [f"warning: {w}" for w in r["warnings"]])
