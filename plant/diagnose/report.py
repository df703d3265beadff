"""The diagnosis report: plain-language finding, report.json (schema in docs/diagnose.md), plots."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from . import locate
from . import plots as plots_mod

SCHEMA = "twin-diagnose/1"


def _rms(ctx, sim, mask, signals):
    idx = [ctx.measured.index(s) for s in signals]
    mse = ctx.per_signal_mse(sim, mask)[idx]
    return float(math.sqrt(np.nanmean(mse))) if idx else math.nan


def _unit(ctx, signal: str) -> str:
    u = ctx.unit(signal)
    return "K" if u == "degC" else u


def _rms_by_unit(ctx, sim0, after, mask, signals) -> dict:
    """Held-out RMSE of the affected signals, one figure per unit (an RMSE over K and W together
    means nothing)."""
    out = {}
    for u in dict.fromkeys(_unit(ctx, s) for s in signals):
        sig = [s for s in signals if _unit(ctx, s) == u]
        out[u] = {"signals": sig, "before": _rms(ctx, sim0, mask, sig), "after": _rms(ctx, after, mask, sig)}
    return out


def _clean(o):
    if isinstance(o, dict):
        return {str(k): _clean(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_clean(v) for v in o]
    if isinstance(o, (np.floating, float)):
        return None if not math.isfinite(float(o)) else float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, np.bool_):
        return bool(o)
    return o


def build(ctx, house, nominal_rows, sim0, results, verdict, best, twins, explained, loc, terms, warnings):
    """report.json's content from the selection (verdict.select) and the localisation (loc), its
    finding included; pipeline.build_report adds the calibration, the further effects and the
    replay's own fits. sim0 / nominal_rows: the nominal twin's measured signals / catalogue rows
    (before); best: the named model (every chosen effect), whose are the after (the nominal's
    again without one)."""
    after = best.sim if best is not None else sim0
    after_rows = best.rows if (best is not None and best.rows is not None) else nominal_rows
    signals = _signal_figures(ctx, sim0, after)
    affected = _affected(ctx, sim0, after, best, loc["mismatched_signals"])
    by_unit = _rms_by_unit(ctx, sim0, after, ctx.held, sorted(affected, key=lambda s: _unit(ctx, s) != "K"))
    energy, energy_held = _energies(ctx, nominal_rows, after_rows, best)
    rep = {
        "schema": SCHEMA,
        "house": house,
        "recording": ctx.rec.source,
        "start": ctx.rec.start,
        "samples": int(len(ctx.rec.time)),
        "interval_s": float(np.median(np.diff(ctx.rec.time))),
        "train_window_h": [float(ctx.rec.time[ctx.train].min() / 3600), float(ctx.rec.time[ctx.train].max() / 3600)],
        "heldout_window_h": [float(ctx.rec.time[ctx.held].min() / 3600), float(ctx.rec.time[ctx.held].max() / 3600)]
        if ctx.held.any() else None,
        "warnings": warnings,
        "verdict": verdict,
        "effect": best.id if (best is not None and verdict == "missing_physics") else None,
        "best_partial_candidate": best.id if (best is not None and verdict != "missing_physics") else None,
        "component": (best.signal or best.component) if best is not None else None,
        "parameters": best.public()["parameters"] if best is not None else {},
        "size": best.effect.size(best.theta, ctx, best.rows) if best is not None else {},
        "indistinguishable_from": twins,
        "explained_share": explained,
        "affected_signals": affected,
        "beyond_tolerance": locate.beyond_tolerance(ctx, sim0, ctx.held),
        # headline: the affected temperatures (K) when there are any, else the first unit's signals
        "affected_heldout_rmse_unit": next(iter(by_unit), None),
        "affected_heldout_rmse_before": by_unit[next(iter(by_unit))]["before"] if by_unit else math.nan,
        "affected_heldout_rmse_after": by_unit[next(iter(by_unit))]["after"] if by_unit else math.nan,
        "affected_heldout_rmse_by_unit": by_unit,
        "cost": {"nominal_train": ctx.cost(sim0, ctx.train), "nominal_heldout": ctx.cost(sim0, ctx.held),
                 "noise_floor": ctx.noise_cost()},
        "signals": signals,
        "guideline_14": _guideline_14_legend(),
        "energy": energy,
        "energy_heldout": energy_held,
        "locate": loc,
        "candidates": [r.public() for r in results],
        "search": terms,
    }
    rep["finding"] = finding(rep, ctx, best)
    return _clean(rep)


def _signal_figures(ctx, sim0, after) -> dict:
    """report.json `signals`: per measured signal with figures, RMSE (whole and held-out), CV(RMSE)
    and NMBE before and after, its subsystem and the hourly Guideline 14 figures."""
    mb_all, ma_all = locate.metrics(ctx, sim0, ctx.train | ctx.held), locate.metrics(ctx, after, ctx.train | ctx.held)
    mb_h, ma_h = locate.metrics(ctx, sim0, ctx.held), locate.metrics(ctx, after, ctx.held)
    whole = ctx.train | ctx.held
    gb, ga = locate.ashrae_hourly(ctx, sim0, whole), locate.ashrae_hourly(ctx, after, whole)
    signals = {}
    for s in ctx.measured:
        if s not in mb_all:
            continue
        g14 = {"before": gb.get(s), "after": ga.get(s)}
        signals[s] = {"unit": ctx.unit(s),
                      "rmse_before": mb_all[s]["rmse"], "rmse_after": ma_all[s]["rmse"],
                      "heldout_rmse_before": mb_h.get(s, {}).get("rmse"),
                      "heldout_rmse_after": ma_h.get(s, {}).get("rmse"),
                      "cvrmse_pct_before": mb_all[s]["cvrmse_pct"], "cvrmse_pct_after": ma_all[s]["cvrmse_pct"],
                      "nmbe_pct_before": mb_all[s]["nmbe_pct"], "nmbe_pct_after": ma_all[s]["nmbe_pct"],
                      "subsystem": ctx.roles.subsystem(s), "guideline_14_hourly": g14}
    return signals


def _affected(ctx, sim0, after, best, mismatched) -> list:
    """report.json `affected_signals`: a sensor effect's own signal; those a plant effect moves
    (beyond the mismatch tolerance), not the structural residual elsewhere it does not touch; else
    those mismatched."""
    affected = mismatched
    if best is not None and best.signal:
        affected = [best.signal]
        if best.rows is not None:  # a plant effect joined the sensor effect: the signals it moves too
            affected += [s for s in locate.moved_signals(ctx, sim0, after, ctx.held) if s != best.signal]
    elif best is not None:
        affected = locate.moved_signals(ctx, sim0, after, ctx.held) or affected
    return affected


def _energies(ctx, nominal_rows, after_rows, best) -> tuple[dict, dict]:
    """report.json `energy` and `energy_heldout` (the whole recording, the held-out window)."""
    energy = locate.energy(ctx, nominal_rows, after_rows if best is not None else None)
    energy_held = locate.energy(ctx, nominal_rows, after_rows if best is not None else None, mask=ctx.held)
    if best is not None and best.kind == "signal" and best.rows is None:
        for e in (energy, energy_held):
            for d in e.values():  # sensor effects (alone) do not change the heat flows
                d["simulated_after_kWh"] = d["simulated_before_kWh"]
                if "error_before_pct" in d:
                    d["error_after_pct"] = d["error_before_pct"]
    return energy, energy_held


def _guideline_14_legend() -> dict:
    """report.json `guideline_14`: how the per-signal Guideline 14 figures are computed and judged."""
    return {"figures": "hourly CV(RMSE) and NMBE per signal, before/after, over the training and "
                       "held-out windows (scored samples only)",
            "cvrmse": "100 / mean(m) * sqrt(sum((m - s)^2) / (n - p))",
            "nmbe": "100 / mean(m) * sum(m - s) / (n - p)",
            "n": "hours with at least half of their samples scored", "p": locate.ASHRAE_P,
            "sign": "measured - simulated", "acceptance_pct": {"cvrmse": locate.ASHRAE_CV_MAX,
                                                                "nmbe": locate.ASHRAE_NMBE_MAX},
            "temperatures": "reported, not judged (the figures depend on the zero of degC)"}


def nominal_refit(nref, ctx, sim0, best) -> dict:
    """report.json `nominal_refit`: the re-fitted nominal parameters of the baseline (and, jointly
    with the selected candidate, its values), with the training/held-out cost of the file values."""
    params = []
    for p in nref.get("parameters", []):
        d = {k: v for k, v in p.items()}
        if best is not None and p["name"] in best.nominal:
            d["fitted_with_candidate"] = best.nominal[p["name"]]
        params.append(d)
    return _clean({"parameters": params,
                   "train_cost_file": nref.get("train_cost_file"),
                   "heldout_cost_file": nref.get("heldout_cost_file"),
                   "train_cost_refit": ctx.cost(sim0, ctx.train) if params else None,
                   "heldout_cost_refit": ctx.cost(sim0, ctx.held) if params else None,
                   "evaluations": nref.get("evaluations", 0),
                   "identifiability": nref.get("identifiability"),
                   "storage_scheme": nref.get("storage_scheme")})


def flag_bounds(rep, results) -> None:
    """report.json `parameters_at_bound`: the calibration (nominal re-fit) and candidate parameters
    that ended on a bound of their range; the finding names them."""
    flags = [{"parameter": p["name"], "value": p["fitted_value"], "bounds": p["bounds"], "stage": "calibration"}
             for p in rep["nominal_refit"]["parameters"] if p.get("at_bound")]
    for key in ("emitter_calibration", "mixer_calibration"):  # the subsystems calibrated alone
        cal = rep.get(key) or {}
        flags += [{"parameter": name, "value": cal["values"][name], "bounds": cal["bounds"][name],
                   "stage": "calibration"} for name in (cal.get("at_bound") or []) if cal.get("calibrated")]
    for r in results:
        for name in getattr(r, "at_bound", []):
            i = [p.name for p in r.effect.params].index(name)
            p = r.effect.params[i]
            flags.append({"parameter": f"{r.id}.{name}", "value": float(r.theta[i]), "bounds": [p.lo, p.hi],
                          "stage": "candidate"})
    rep["parameters_at_bound"] = flags
    cal = [f"{f['parameter']} = {f['value']:.4g}" for f in flags if f["stage"] == "calibration"]
    if cal:
        rep["finding"] += (" Calibration parameters on a bound (the nominal structure absorbs a difference it "
                           "cannot represent): " + ", ".join(cal) + ".")


def _mode_phrase(rep, affected):
    modes = [m for m in rep["locate"]["modes"] if m["time_share"] >= 0.02]
    if not modes:
        return None, {}
    def conc(m):
        return m["concentration"]
    m = max(modes, key=conc)
    return m["mode"], m["bias"]


def finding(rep, ctx, best) -> str:
    v = rep["verdict"]
    aff = rep["affected_signals"]
    if v == "no_missing_physics":
        txt = ("No missing physics found: the twin, driven by the recorded commands, reproduces the "
               f"recording within replay and sensor accuracy; no candidate beats the nominal model on "
               f"held-out data (held-out cost {rep['cost']['nominal_heldout']:.3g}, "
               f"sensor-noise floor {rep['cost']['noise_floor']:.3g}).")
        if aff:
            sub = rep["locate"].get("subsystems") or [{}]
            txt = ("No missing physics found: the remaining mismatch (largest in the "
                   f"{sub[0].get('subsystem', '?')} subsystem) stays within the replay's accuracy on an "
                   f"independent plant (temperature bias <= {locate.MODEL_TOL_K:g} K, Guideline 14 hourly "
                   "figures met) and no candidate explains it on held-out data.")
        return txt
    mode, bias = _mode_phrase(rep, aff)
    parts = []
    shown = aff[:4]
    if shown:
        lower = [s for s in shown if bias.get(s, 0.0) < 0]
        higher = [s for s in shown if bias.get(s, 0.0) >= 0]
        desc = []
        if lower:
            desc.append(f"{', '.join(lower)} {'is' if len(lower) == 1 else 'are'} lower than simulated")
        if higher:
            desc.append(f"{', '.join(higher)} {'is' if len(higher) == 1 else 'are'} higher than simulated")
        parts.append((f"During '{mode}' periods (where the error concentrates), " if mode else "")
                     + " and ".join(desc))
    if v == "missing_physics":
        txt = (f"best explained by {best.effect.id} ({best.effect.summary(best.theta, ctx, best.rows)}"
               + (f" on {best.signal}" if best.signal else "") + ")")
        rms = [f"{'the affected temperatures' if u == 'K' else ', '.join(d['signals'])} "
               f"{d['before']:.3g} {u} -> {d['after']:.3g} {u}"
               for u, d in rep["affected_heldout_rmse_by_unit"].items()
               if d["before"] is not None and d["after"] is not None]
        if rms:
            txt += "; held-out RMSE of " + ", of ".join(rms)
        chp = rep["energy"].get("chp", {})
        if chp.get("error_before_pct") is not None and chp.get("error_after_pct") is not None:
            txt += (f"; CHP heat ({chp['signal']}) error {chp['error_before_pct']:+.1f} % -> "
                    f"{chp['error_after_pct']:+.1f} %")
        if rep["indistinguishable_from"]:
            txt += ("; the sensors cannot tell it apart from " + ", ".join(rep["indistinguishable_from"]))
        parts.append(txt)
    else:
        txt = "unexplained mismatch: no catalogue candidate explains it"
        if best is not None:
            txt += (f" (best partial candidate {best.id} removes only {100 * rep['explained_share']:.0f} % of "
                    f"the held-out excess error)")
        terms = [t["term"] for s in rep["search"] for t in s["terms"]][:4]
        if terms:
            txt += "; residual terms proposed by the search: " + "; ".join(dict.fromkeys(terms))
        parts.append(txt)
    return "; ".join(parts) + "."


def write_json(rep, out) -> Path:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    p = out / "report.json"
    p.write_text(json.dumps(_clean(rep), indent=2))
    return p


def write(rep, out, ctx, nominal_rows, best, plots=True) -> None:
    """report.md and, with plots, the PNGs; rep["plots"] names the PNGs written (report.md links them)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rep["plots"] = plots_mod.write_plots(rep, out, ctx, nominal_rows, best) if plots else {}
    lines = [f"# twin diagnose: {rep['recording']}", "", rep["finding"], "", f"verdict: {rep['verdict']}"]
    if rep["effect"]:
        lines.append(f"effect: {rep['effect']} ({rep['component']})")
        for k, p in rep["parameters"].items():
            lines.append(f"  {k} = {p['value']:.4g} ± {p['stderr'] if p['stderr'] is not None else float('nan'):.2g} {p['unit']}")
    nr = rep.get("nominal_refit") or {}
    if nr.get("parameters"):
        f = lambda x: "-" if x is None else f"{x:.4g}"  # noqa: E731
        lines += ["", "nominal re-fit (narrow bounds; the 'before' baseline uses the fitted values):", "",
                  "| parameter | file | fitted (nominal) | fitted (with candidate) | bounds |", "|---|---|---|---|---|"]
        for p in nr["parameters"]:
            lines.append(f"| {p['name']} [{p['unit']}] | {f(p['file_value'])} | {f(p['fitted_value'])}"
                         f"{' (at bound)' if p['at_bound'] else ''} | {f(p.get('fitted_with_candidate'))} | "
                         f"{f(p['bounds'][0])} .. {f(p['bounds'][1])} |")
        lines.append(f"\ncost with the file values: training {f(nr['train_cost_file'])}, held-out "
                     f"{f(nr['heldout_cost_file'])}; re-fitted: training {f(nr['train_cost_refit'])}, "
                     f"held-out {f(nr['heldout_cost_refit'])}")
    lines += ["", "| signal | RMSE before | after | held-out before | after |", "|---|---|---|---|---|"]
    for s, d in rep["signals"].items():
        f = lambda x: "-" if x is None else f"{x:.3g}"  # noqa: E731
        lines.append(f"| {s} | {f(d['rmse_before'])} | {f(d['rmse_after'])} | {f(d['heldout_rmse_before'])} | "
                     f"{f(d['heldout_rmse_after'])} |")
    g = lambda d, k: "-" if not d or d.get(k) is None else f"{d[k]:.3g}"  # noqa: E731
    lines += ["", "ASHRAE Guideline 14, hourly (CV(RMSE) = 100/mean(m) sqrt(sum((m-s)^2)/(n-p)), "
              f"NMBE = 100/mean(m) sum(m-s)/(n-p), p = {rep['guideline_14']['p']}, m measured, s simulated; "
              "acceptance CV(RMSE) <= 30 %, |NMBE| <= 10 %, temperatures reported only):", "",
              "| signal | subsystem | CV(RMSE) before % | after % | NMBE before % | after % |", "|---|---|---|---|---|---|"]
    for s, d in rep["signals"].items():
        b, a = d["guideline_14_hourly"]["before"], d["guideline_14_hourly"]["after"]
        lines.append(f"| {s} | {d['subsystem']} | {g(b, 'cvrmse_pct')} | {g(a, 'cvrmse_pct')} | "
                     f"{g(b, 'nmbe_pct')} | {g(a, 'nmbe_pct')} |")
    rp = rep["locate"].get("replay", {})
    lines += ["", f"replayed plant: {rp.get('plant')}" + (f" (measured boundaries: "
              f"{', '.join(f'{k} <- {v}' for k, v in rp.get('boundaries', {}).items())})" if rp.get("cut") else ""),
              "", "## Subsystems", "", "localisation (held-out window; plots: measured, nominal twin = before, "
              "fitted twin = after, held-out window shaded):", "",
              "| subsystem | held-out error share % | mode where it concentrates | mismatched signals | plot |",
              "|---|---|---|---|---|"]
    files = rep["plots"].get("subsystems", {})
    for d in rep["locate"].get("subsystems", []):
        mode = f"{d['mode']} (x{d['mode_concentration']:.2f})" if d.get("mode") else "-"
        img = f"![{d['subsystem']}]({files[d['subsystem']]})" if d["subsystem"] in files else "-"
        lines.append(f"| {d['subsystem']} | {100 * d['error_share']:.0f} | {mode} | "
                     f"{', '.join(d['mismatched_signals']) or '-'} | {img} |")
    if rep.get("parameters_at_bound"):
        lines += ["", "parameters on a bound of their range:"] + [
            f"  - {f['parameter']} = {f['value']:.4g} (bounds {f['bounds'][0]:.4g} .. {f['bounds'][1]:.4g}, {f['stage']})"
            for f in rep["parameters_at_bound"]]
    lines += ["", "energy [kWh]:"]
    for c, d in rep["energy"].items():
        via = f" ({d['signal']})" if d.get("signal") else ""
        lines.append(f"  {c}{via}: " + ", ".join(f"{k} {v:.3g}" for k, v in d.items() if isinstance(v, float)))
    if rep["warnings"]:
        lines += ["", "warnings:"] + [f"  - {w}" for w in rep["warnings"]]
    (out / "report.md").write_text("\n".join(lines) + "\n")
