"""Locate the mismatch: per-signal metrics, time windows, operating modes, energy per component."""
from __future__ import annotations

import math
import warnings

import numpy as np

from ..units import UNITS
from ..water import CP, RHO
from .context import MISMATCH_TOL

KWH = UNITS["kWh"].factor  # J in one kWh (3.6e6)


def metrics(ctx, sim: np.ndarray, mask: np.ndarray) -> dict:
    """RMSE, CV(RMSE) and NMBE (ASHRAE Guideline 14 style, in %) per measured signal."""
    out = {}
    r = ctx.residual(sim)
    for j, s in enumerate(ctx.measured):
        m = mask[: len(r)] & np.isfinite(r[:, j])
        if not m.any():
            continue
        e = r[m, j]
        mean_meas = float(np.mean(ctx.meas[m, j]))
        denom = abs(mean_meas) if abs(mean_meas) > 1e-9 else np.nan
        out[s] = {"rmse": float(np.sqrt(np.mean(e ** 2))), "bias": float(np.mean(e)),
                  "robust": float(1.4826 * np.median(np.abs(e - np.median(e)))),
                  "cvrmse_pct": float(100 * np.sqrt(np.mean(e ** 2)) / denom),
                  "nmbe_pct": float(100 * np.sum(e) / (len(e) * denom))}
    return out


# ASHRAE Guideline 14-2014 calibration figures on hourly means (measured m, simulated s):
#   CV(RMSE) = 100 / mean(m) * sqrt(sum((m - s)^2) / (n - p))
#   NMBE     = 100 / mean(m) * sum(m - s) / (n - p)
# n = hours with at least half of their samples scored, p = 1 (the Guideline's value for a
# calibrated simulation), sign: measured - simulated (a positive NMBE: the twin reads low). The
# Guideline's hourly acceptance: CV(RMSE) <= 30 %, |NMBE| <= 10 %. It was written for energy and
# flows; for a temperature in degC the figures depend on the scale's zero and are reported, not judged.
ASHRAE_P = 1
ASHRAE_CV_MAX, ASHRAE_NMBE_MAX = 30.0, 10.0


def ashrae_hourly(ctx, sim: np.ndarray, mask: np.ndarray) -> dict:
    """Hourly CV(RMSE) and NMBE [%] per measured signal over the samples in mask."""
    r = ctx.residual(sim)
    n = len(r)
    t = ctx.rec.time[:n]
    hour = np.floor((t - t[0]) / 3600.0).astype(int)
    dt = float(np.median(np.diff(t))) if n > 1 else 3600.0
    need = max(1, int(0.5 * round(3600.0 / dt)))
    out = {}
    for j, s in enumerate(ctx.measured):
        ok = mask[:n] & np.isfinite(r[:, j])
        if not ok.any():
            continue
        cnt = np.bincount(hour[ok], minlength=hour[-1] + 1)
        sm = np.bincount(hour[ok], weights=ctx.meas[:n][ok, j], minlength=hour[-1] + 1)
        se = np.bincount(hour[ok], weights=r[ok, j], minlength=hour[-1] + 1)
        keep = cnt >= need
        nh = int(keep.sum())
        if nh <= ASHRAE_P:
            continue
        m_h, e_h = sm[keep] / cnt[keep], se[keep] / cnt[keep]
        mean = float(np.mean(m_h))
        if abs(mean) < 1e-9:
            continue
        cv = 100.0 * math.sqrt(float(np.sum(e_h ** 2)) / (nh - ASHRAE_P)) / abs(mean)
        nmbe = 100.0 * float(np.sum(e_h)) / ((nh - ASHRAE_P) * mean)
        unit = ctx.unit(s)
        out[s] = {"hours": nh, "cvrmse_pct": cv, "nmbe_pct": nmbe,
                  "meets_guideline_14": (cv <= ASHRAE_CV_MAX and abs(nmbe) <= ASHRAE_NMBE_MAX)
                  if unit != "degC" else None}
    return out


# The replay's accuracy on a plant it shares no code with: below it a mismatch that no candidate
# explains is not reported as missing physics. Temperatures: a held-out bias of MODEL_TOL_K
# (labsim's no-effect recording: storage, generator and header biases up to 3.9 K from its own
# storage discretisation, coil and header models); other signals: Guideline 14's hourly
# acceptance (ASHRAE_CV_MAX, ASHRAE_NMBE_MAX) on hours where the signal is non-zero on average.
MODEL_TOL_K = 5.0


# Guideline 14's hourly CV(RMSE) limit judges scatter as well as bias. On a rig the twin shares
# no code with, a replay's scatter comes from how its units start, stop and modulate against the
# lab's (rigsim's boiler: 33-37 % held-out with 2 % bias and no effect), which no calibration
# removes and which is there in every window. The scatter a flow or power may show is therefore
# estimated from the recording: the calibrated nominal's CV(RMSE) on the training window times
# SCATTER_MARGIN (two days estimate it to about that), when that is above the Guideline's 30 %.
# The bias limit stays the Guideline's 10 %: a missing effect on energy (a fouled boiler, 12 %) is
# a bias. Chosen on rigsim's realisation-1 null_a, reported on labsim's realisation 2 and the rest.
SCATTER_MARGIN = 1.25


def scatter_limit(ctx, s: str) -> float:
    """The hourly CV(RMSE) [%] flow or power s may show on held-out data (see SCATTER_MARGIN)."""
    if ctx.nominal_sim is None:
        return ASHRAE_CV_MAX
    train = ashrae_hourly(ctx, ctx.nominal_sim, ctx.train).get(s)
    return max(ASHRAE_CV_MAX, SCATTER_MARGIN * train["cvrmse_pct"]) if train else ASHRAE_CV_MAX


def within_accuracy(ctx, s: str, hourly: dict) -> bool:
    """A flow or power's held-out hourly figures (ashrae_hourly's entry) within the replay's
    accuracy: |NMBE| <= Guideline 14's and CV(RMSE) <= scatter_limit."""
    return abs(hourly["nmbe_pct"]) <= ASHRAE_NMBE_MAX and hourly["cvrmse_pct"] <= scatter_limit(ctx, s)


def beyond_tolerance(ctx, sim: np.ndarray, mask: np.ndarray) -> list[str]:
    """Signals whose held-out mismatch is well above the replay's accuracy (MODEL_TOL_K;
    flows and powers: within_accuracy)."""
    m = metrics(ctx, sim, mask)
    g = ashrae_hourly(ctx, sim, mask)
    out = []
    for s in ctx.measured:
        if s not in m:
            continue
        if ctx.unit(s) == "degC":
            if abs(m[s]["bias"]) > MODEL_TOL_K:
                out.append(s)
        elif s in g and not within_accuracy(ctx, s, g[s]):
            out.append(s)
    return out


def subsystems(ctx, sim: np.ndarray, mask: np.ndarray, mismatched: list[str]) -> list[dict]:
    """Where the mismatch sits: per subsystem (roles.py) its share of the normalised
    squared error, its signals with a mismatch, and the operating mode it concentrates in."""
    r = ctx.residual(sim)
    n = len(r)
    z = (r / ctx.scale) ** 2
    z = np.where(mask[:n, None], z, np.nan)
    per = np.nanmean(z, axis=0)
    total = float(np.nansum(per)) or 1e-12
    groups: dict = {}
    for j, s in enumerate(ctx.measured):
        groups.setdefault(ctx.roles.subsystem(s), []).append(j)
    out = []
    for name, idx in groups.items():
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # samples where none of its signals is scored
            zi = np.nanmean(z[:, idx], axis=1)
        best = None
        for k, f in ctx.flags.items():
            sel = f[:n] & mask[:n] & np.isfinite(zi)
            if sel.sum() < 0.02 * n or (~f[:n] & mask[:n]).sum() < 0.02 * n:
                continue
            ratio = float(np.nanmean(zi[sel]) / max(np.nanmean(zi[mask[:n] & np.isfinite(zi)]), 1e-12))
            if best is None or ratio > best[1]:
                best = (ctx.modes[k], ratio)
        out.append({"subsystem": name, "error_share": float(np.nansum(per[idx]) / total),
                    "signals": [ctx.measured[j] for j in idx],
                    "mismatched_signals": [ctx.measured[j] for j in idx if ctx.measured[j] in mismatched],
                    "mode": best[0] if best else None, "mode_concentration": best[1] if best else None})
    out.sort(key=lambda d: -d["error_share"])
    return out


def mismatched_signals(ctx, sim, mask, tol: float = MISMATCH_TOL, tol_rms: float = 1.0) -> list[str]:
    """Signals with a mismatch beyond replay and sensor accuracy (held-out window):
      * persistent: |bias| or the robust spread of the residual above tol x scale + 3 noise sigma
        (not switching spikes: a command edge replayed up to half a sample late makes short
        spikes that a median-based spread ignores);
      * transient (temperatures only): RMS residual above tol_rms x scale + 3 noise sigma, i.e.
        1 K. A lagging sensor errs only while its temperature moves: large but short-lived
        errors the median ignores. Temperatures are states, so command-timing spikes stay small
        (a noise-only replay of the truth: RMS <= 0.8 K); flows and powers switch with the
        commands, where the RMS of a correct model is dominated by edge timing.
    A signal of a subsystem calibrated alone on that very signal (ctx.calibrated: the radiator's
    return) keeps no allowance for replay structure: a mismatch is above 3 noise sigma."""
    m = metrics(ctx, sim, mask)
    out = []
    for j, s in enumerate(ctx.measured):
        if s not in m:
            continue
        own = 0.0 if s in ctx.calibrated else 1.0
        lim = ctx.limit(j, own * tol)
        lim_rms = ctx.limit(j, own * tol_rms)
        transient = ctx.unit(s) == "degC" and m[s]["rmse"] > lim_rms
        if abs(m[s]["bias"]) > lim or m[s]["robust"] > lim or transient:
            out.append(s)
    return out


def moved_signals(ctx, before, after, mask, tol: float = MISMATCH_TOL) -> list[str]:
    """Signals a fitted effect acts on: where its run differs from the run without it by more
    than the persistent-mismatch tolerance of mismatched_signals (tol x scale + 3 noise sigma, RMS
    over the scored samples of the window), whether the change brings them closer or not."""
    m = mask[: min(len(before), len(after))]
    d = np.where(ctx.ok[: len(m)], after[: len(m)] - before[: len(m)], np.nan)[m]
    out = []
    for j, s in enumerate(ctx.measured):
        with np.errstate(invalid="ignore"):
            rms = float(np.sqrt(np.nanmean(d[:, j] ** 2))) if np.isfinite(d[:, j]).any() else 0.0
        if rms > ctx.limit(j, tol):
            out.append(s)
    return out


def windows(ctx, sim: np.ndarray, top: int = 5, hours: float = 1.0) -> list[dict]:
    """Time windows that carry the error: 1-h rolling mean of the normalised squared residual."""
    r = ctx.residual(sim)
    z = np.nan_to_num((r / ctx.scale) ** 2)
    tot = z.mean(axis=1)
    t = ctx.rec.time[: len(tot)]
    dt = float(np.median(np.diff(t)))
    w = max(1, int(round(hours * 3600 / dt)))
    roll = np.convolve(tot, np.ones(w) / w, mode="same")
    thr = max(3.0 * np.median(roll), np.percentile(roll, 90))
    hot = roll > thr
    out = []
    i = 0
    n = len(hot)
    while i < n:
        if hot[i]:
            j = i
            while j < n and hot[j]:
                j += 1
            seg = slice(i, j)
            share = float(tot[seg].sum() / max(tot.sum(), 1e-12))
            per = z[seg].mean(axis=0)
            order = np.argsort(per)[::-1][:3]
            modes = {k: float(np.mean(v[seg])) for k, v in ctx.flags.items()}
            out.append({"start_h": float(t[i] / 3600), "end_h": float(t[j - 1] / 3600), "error_share": share,
                        "signals": [ctx.measured[k] for k in order],
                        "modes": {ctx.modes[k]: round(v, 2) for k, v in modes.items()}})
            i = j
        else:
            i += 1
    out.sort(key=lambda d: -d["error_share"])
    return out[:top]


def modes(ctx, sim: np.ndarray, mask: np.ndarray | None = None) -> list[dict]:
    """Error concentration per operating mode (combinations of the generators', the heating and
    the charging pumps' states)."""
    r = ctx.residual(sim)
    n = len(r)
    mask = np.ones(n, bool) if mask is None else mask[:n]
    z = np.nan_to_num((r / ctx.scale) ** 2)
    tot = z.mean(axis=1)
    f = ctx.flags
    keys = [k for k in (*(f"{g.name}_on" for g in ctx.roles.generators), "heating_on", "dhw_on") if k in f]
    words = ctx.modes
    code = sum((f[k][:n].astype(int) << i) for i, k in enumerate(keys))
    out = []
    total = float(tot[mask].sum()) or 1e-12
    for c in np.unique(code[mask]):
        sel = mask & (code == c)
        time_share = float(sel.sum() / mask.sum())
        if time_share < 0.01:
            continue
        err_share = float(tot[sel].sum() / total)
        name = ", ".join(words[k] if (c >> i) & 1 else words[k][: -len(" on")] + " off"
                         for i, k in enumerate(keys))
        bias = {}
        for j, s in enumerate(ctx.measured):
            e = r[sel, j]
            e = e[np.isfinite(e)]
            if e.size:
                bias[s] = float(e.mean())
        out.append({"mode": name, "time_share": time_share, "error_share": err_share,
                    "concentration": err_share / time_share, "bias": bias})
    out.sort(key=lambda d: -d["error_share"])
    return out


def heat_signal(ctx, comp: str) -> str:
    """The heat signal a component is judged on: the recorded one, so that the twin is read
    through the same instrument (a unit's own heat counter, chp.Q_flow_meter, reads its pump's
    flow only; a heat meter in the branch, chp.Q_flow, reads all of it)."""
    for name in (f"{comp}.Q_flow_meter", f"{comp}.Q_flow"):
        if name in ctx.roles.catalogue and ctx.rec.has(name):
            return name
    return f"{comp}.Q_flow"


def _heat(ctx, rows_or_meas, kind: str, comp: str, mask=None):
    """Integrated heat [kWh] of a component from its recorded heat signal, or m cp dT when none
    is recorded (over the samples in mask; all samples when None)."""
    t = ctx.rec.time
    dt = np.diff(t, prepend=t[0])
    if mask is not None:
        dt = np.where(mask[: len(dt)], dt, 0.0)
    def get(name):
        if kind == "sim":
            return rows_or_meas[:, ctx.index(name)]
        return ctx.rec.data.get(name)
    q = get(heat_signal(ctx, comp))
    if q is None and kind == "meas":
        m, a, b = get(f"{comp}.m_flow"), get(f"{comp}.T_sup"), get(f"{comp}.T_ret")
        if m is None or a is None or b is None:
            return None
        q = m * CP * (a - b)
    q = np.nan_to_num(q[: len(dt)])
    return float(np.sum(q * dt[: len(q)]) / KWH)


def energy(ctx, nominal_rows, fitted_rows=None, mask=None) -> dict:
    """Heat per generator/consumer and storage energy change: measured vs simulated (mask: the
    samples integrated, e.g. ctx.held; the storage change is only reported for the whole)."""
    out = {}
    for comp in (u.name for u in (*ctx.roles.generators, *ctx.roles.circuits, *ctx.roles.chargers)):
        meas = _heat(ctx, None, "meas", comp, mask)
        if meas is None:
            continue
        before = _heat(ctx, nominal_rows, "sim", comp, mask)
        d = {"signal": heat_signal(ctx, comp), "measured_kWh": meas, "simulated_before_kWh": before,
             "error_before_pct": 100 * (before - meas) / abs(meas) if abs(meas) > 1e-6 else None}
        if fitted_rows is not None:
            after = _heat(ctx, fitted_rows, "sim", comp, mask)
            d["simulated_after_kWh"] = after
            d["error_after_pct"] = 100 * (after - meas) / abs(meas) if abs(meas) > 1e-6 else None
        out[comp] = d
    _, volume, names = ctx.roles.buffer or (None, 0.0, ())
    if mask is None and names and all(ctx.rec.has(n) for n in names):
        mass = RHO * volume
        def dE(T):
            T = np.asarray(T)
            return float(mass * CP * (np.nanmean(T[-1]) - np.nanmean(T[0])) / KWH)
        meas = dE(np.column_stack([ctx.rec.data[n] for n in names])[[0, -1]])
        idx = [ctx.index(n) for n in names]
        d = {"measured_kWh": meas, "simulated_before_kWh": dE(nominal_rows[[0, -1]][:, idx])}
        if fitted_rows is not None:
            d["simulated_after_kWh"] = dE(fitted_rows[[0, -1]][:, idx])
        out["storage (change of stored heat)"] = d
    return out
