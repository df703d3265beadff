"""`twin diagnose`: find the missing physics behind the mismatch between a recording and the twin.

    from plant.diagnose import diagnose, recording_io
    rec = recording_io.load("lab.csv", "columns.toml")
    report = diagnose(rec, house="house1", out="report/")     # dict, also report/report.json

Stages: replay (replay.py) -> locate (locate.py) -> hypothesise (effects/, search.py) ->
fit (fit.py) -> judge and select (verdict.py) -> report (report.py). Method and report.json schema: docs/diagnose.md.
"""
from __future__ import annotations

import time

from ..catalogue import CATALOGUE
from . import calibration, fit, forward, locate, parallel, pipe_sensor, recording_io, replay, search  # noqa: F401
from . import unit_modes
from . import verdict as verdict_mod
from .context import Context
from .effects import catalogue


def diagnose(rec, house: str = "house1", out=None, train_days: float = 2.0, effects=None,
             plots: bool = True, log=print, refit_nominal: bool = True, jobs: int | None = None,
             require_cut: bool = False) -> dict:
    """jobs: processes for the candidate fits (default: the CPUs this process may use);
    require_cut: refuse a recording that allows no cut (cut.select)."""
    timing = {}
    t0 = time.perf_counter()
    warnings = list(rec.warnings)
    warnings += replay.check(rec)
    rp = replay.Replayer(rec, house, require_cut=require_cut)
    ctx = Context.build(rec, train_days=train_days, simulated=rp.simulated)
    rp.t_train = ctx.t_split
    radiator_cal = rp.calibrate_radiator(ctx.train)
    if radiator_cal and radiator_cal["calibrated"]:
        ctx.calibrated = tuple(replay.cut_mod.RADIATOR_OUTPUTS)
        log(f"radiator alone: {radiator_cal['elements']} elements, " + ", ".join(
            f"{k} {v:.4g}" for k, v in radiator_cal["values"].items()) + f", return RMS {radiator_cal['rms_K']:.3g} K")
    mixer_cal = rp.calibrate_mixer(ctx.train)
    if mixer_cal and mixer_cal["calibrated"]:
        log("mixing station alone: " + ", ".join(f"{k} {v:.4g}" for k, v in mixer_cal["values"].items())
            + f", supply RMS {mixer_cal['rms_file_K']:.3g} -> {mixer_cal['rms_K']:.3g} K")
    nominal_rows = rp.run()
    warnings += rp.notes + rp.boundary_check(nominal_rows)
    # a unit's own modes the twin lacks (a boiler's lock-out) are not scored (unit_modes.py)
    modes = unit_modes.identify(rec, nominal_rows, CATALOGUE.index)
    unit_modes.apply(ctx, modes)
    sim_file = nominal_rows[:, ctx.cols]
    # nominal re-fit (calibration.NOMINAL_REFIT, narrow bounds): the baseline is the best nominal twin
    nref = {"parameters": [], "params": []}
    if refit_nominal:
        nref = calibration.refit_nominal(ctx, rp, house)
        ctx.nominal_ranges = calibration.ranges(nref)
        nominal_rows = rp.run()
        nref["train_cost_file"] = ctx.cost(sim_file, ctx.train)
        nref["heldout_cost_file"] = ctx.cost(sim_file, ctx.held)
        if nref.get("storage_scheme"):
            log(f"storage scheme: {nref['storage_scheme']['chosen']}")
        log("nominal re-fit: " + ", ".join(f"{p['name']} {p['file_value']:.4g} -> {p['fitted_value']:.4g}"
                                           for p in nref["parameters"]))
    sim0 = nominal_rows[:, ctx.cols]
    pipe_fit = dict(rp.pipe_fit)
    ctx.height_fit = dict(rp.height_fit)
    ctx.nominal_rows = nominal_rows  # the replayed states, for candidates' plausible()
    ctx.nominal_sim = sim0
    # the subsystems replayed alone between measured interfaces: candidates on them are judged there
    ctx.alone = {"instances": {"mixer"}, "signals": list(replay.cut_mod.CIRCUIT_OUTPUTS)} if rp.circuit else None
    J0t, J0h = ctx.cost(sim0, ctx.train), ctx.cost(sim0, ctx.held)
    timing["replay_nominal"] = time.perf_counter() - t0
    log(f"nominal replay: training cost {J0t:.4g}, held-out cost {J0h:.4g} "
        f"({len(ctx.measured)} measured signals)")

    # locate
    t1 = time.perf_counter()
    affected = locate.mismatched_signals(ctx, sim0, ctx.held)
    loc = {"replay": {"plant": rp.plant_name, "cut": rp.cut.name if rp.cut else None,
                      "boundaries": dict(rp.bound), "mixing_station_alone": rp.circuit},
           "subsystems": locate.subsystems(ctx, sim0, ctx.held, affected),
           "windows": locate.windows(ctx, sim0), "modes": locate.modes(ctx, sim0)[:6],
           "mismatched_signals": affected}
    timing["locate"] = time.perf_counter() - t1

    # hypothesise and fit (simulate-kind candidates in parallel processes: each is independent)
    t2 = time.perf_counter()
    results, todo = [], []
    for e in (effects if effects is not None else catalogue()):
        ok, why = e.plausible(ctx) if e.available else (False, e.description)
        if not ok:
            results.append(fit.Result(e.id, e.component, e.kind, False, why, effect=e))
        else:
            results.append(None)
            todo.append((len(results) - 1, e))
    sims = [(i, e) for i, e in todo if e.kind == "simulate"]
    for (i, e), r in zip(sims, parallel.fit_all([e for _, e in sims], ctx, rp, J0t, nref["params"], jobs)):
        results[i] = r
    for i, e in todo:
        if e.kind != "simulate":
            results[i] = fit.fit_signal(e, ctx, sim0, rp)
    for i, e in todo:
        r = results[i]
        log(f"  {e.id:<20} {r.signal or '':<24} theta {r.theta[0] if r.theta else float('nan'):.4g}  "
            f"held-out cost {r.held_cost:.4g}")
    verdict_mod.judge(results, ctx, J0t, J0h)
    verdict, best, twins, explained = verdict_mod.select(results, ctx, sim0, affected)
    chosen = forward.extend(best, results, twins, ctx, rp) if verdict == "missing_physics" else []
    # the report's "after": the model that holds every chosen effect (the best alone when only it)
    final = forward.final(chosen) if len(chosen) > 1 else best
    timing["fit"] = time.perf_counter() - t2

    t3 = time.perf_counter()
    terms = search.search(ctx, nominal_rows, affected) if verdict != "no_missing_physics" else []
    timing["search"] = time.perf_counter() - t3

    from . import report as _report

    t4 = time.perf_counter()
    rep = _report.build(ctx, house, nominal_rows, sim0, results, verdict, final, twins, explained, loc,
                        terms, warnings)
    rep["nominal_refit"] = _report.nominal_refit(nref, ctx, sim0, best)
    rep["effects"] = forward.public(chosen, ctx)
    if len(chosen) > 1:
        rep["finding"] += "; together with " + ", ".join(
            f"{r.id} ({r.effect.summary(r.theta, ctx, r.rows)}{' on ' + r.signal if r.signal else ''}, held-out "
            f"gain {100 * r.held_gain:.0f} % over the model before it)" for r in chosen[1:])
    rep["radiator_calibration"] = radiator_cal
    rep["mixer_calibration"] = mixer_cal
    # the nominal twin's fits, and the named model's where a plant effect changed its flows
    named = final.pipe if final is not None else {}
    rep["pipe_sensors"] = {flow: {**pipe_sensor.public(f), "T_plant_room_degC": rp._T_room,
                                  "T_plant_room_from": rp._T_room_from,
                                  "named_model": pipe_sensor.public(named[flow]) if flow in named else None}
                           for flow, f in pipe_fit.items()}
    rep["unit_modes"] = unit_modes.public(modes)
    heights = rp.tank_heights()
    rep["storage_sensor_places"] = {s: h.public(heights[s.rpartition(".T_sensor_")[0]])
                                    for s, h in ctx.height_fit.items()}
    _report.flag_bounds(rep, results)
    if out is not None:
        _report.write(rep, out, ctx, nominal_rows, final, plots=plots)
    timing["report"] = time.perf_counter() - t4
    timing["total"] = time.perf_counter() - t0
    rep["timing_s"] = timing
    if out is not None:
        _report.write_json(rep, out)
    return rep
