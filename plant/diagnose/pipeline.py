"""The diagnosis as stages, each a function of its inputs that returns an immutable value:

    prepare -> outlets -> calibrate -> locate_mismatch -> fit_candidates -> select -> build_report

(outlets: the generators the recording runs otherwise than the twin's model of them, replayed
from their measured outlets; prepare runs again with them when there are any.)

No stage changes what an earlier one returned: a calibration gives a new replayer
(Replayer.with_calibration), the nominal replay a new context (Context.with_baseline), the unit
modes masked another (unit_modes.apply). `diagnose` runs them in order and times each.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

from . import calibration, fit, forward, locate, parallel, pipe_sensor, replay, requirements, search, unit_modes
from . import cut as cut_mod
from . import unrepresented
from . import report as report_mod
from . import verdict as verdict_mod
from .context import Context
from ..declaration import load
from .effects import UnitEffect, catalogue


@dataclass(frozen=True)
class Prepared:
    """The recording checked and framed: its context, the replayer, and what replay noted."""
    ctx: Context
    replayer: replay.Replayer
    warnings: tuple


@dataclass(frozen=True)
class Baseline:
    """The best nominal twin: the context judged against its replay, the calibrated replayer every
    later run starts from, and the calibrations' report entries."""
    ctx: Context
    replayer: replay.Replayer
    nominal: replay.Replay
    refit: dict                 # calibration.refit_nominal's entry (its "params": re-fitted with candidates)
    emitter: dict | None        # the emitter replayed alone, calibrated (Replayer.calibrate_emitter)
    mixer: dict | None          # the mixing station replayed alone, calibrated
    modes: dict                 # unit_modes.identify
    warnings: tuple
    train_cost: float
    held_cost: float


@dataclass(frozen=True)
class Location:
    """Where the nominal twin and the recording differ."""
    affected: tuple             # mismatched signals on the held-out window
    summary: dict               # report.json "locate"


@dataclass(frozen=True)
class Selection:
    """The verdict and the model it names."""
    results: tuple              # every candidate's fit.Result, judged (verdict.judge, verdict.select)
    verdict: str
    best: object
    twins: tuple
    explained: object
    chosen: tuple               # the named effect and the ones joined on top of it (forward.extend)
    final: object               # the model holding every chosen effect (None: nothing named)
    terms: tuple                # search.search's regression terms


def prepare(rec, house: str, train_days: float, require_cut: bool, generators: dict | None = None) -> Prepared:
    """Check the recording, choose the replayed plant (a cut where it measures enough; with the
    `generators` given at their measured outlets: outlets), frame the training and held-out
    windows."""
    requirements.check_house(house)
    warnings = list(rec.warnings) + requirements.check(rec, house)
    rp = replay.Replayer(rec, house, require_cut=require_cut, generators=tuple(generators or ()))
    for unit, m in (generators or {}).items():
        warnings.append(f"{unit}: the recording runs it otherwise than the twin's model of it does (their running "
                        f"states differ at {m['samples']} samples, {100 * m['share_of_running']:.0f} % of its running "
                        f"samples, more than the {m['lab_switches']} at which it switches): replayed at its measured "
                        "outlet temperature and flow (its gas from its efficiency), and no effect on it is judged")
    simulated = rp.simulated
    for unit, runs in rp.unfollowed.items():
        # the twin's own control runs it (Replayer); its signals, sampled between pulses, are not
        # compared, and said so
        simulated = {s for s in simulated if s.split(".", 1)[0] != unit}
        warnings.append(f"{unit}: it runs {runs} times for less than the recording's scan (runs of its "
                        f"command one sample long, or its counter rising between samples that read it off): "
                        f"it switches faster than the scan, which a replay cannot follow; the twin's own "
                        f"control runs it and its signals are not compared (record its command or flow "
                        f"faster, or as a run-time count)")
    ctx = Context.build(rec, train_days=train_days, simulated=simulated, roles=rp.roles)
    return Prepared(ctx, rp.with_calibration(t_train=ctx.t_split), tuple(warnings))


def outlets_of(rp) -> tuple:
    """The generators a replayer runs at their measured outlets."""
    return rp.cut.generators if rp.cut else ()


def outlets(p: Prepared) -> dict:
    """{generator: its unit_modes entry} for the generators to replay from their measured outlet
    temperature and flow: those whose running state in the file-valued nominal replay differs
    from the recording's at more samples than it switches (unit_modes.run_otherwise: run otherwise
    than the twin's model runs, a boiler cycling or locking out on its own limits), where the recording
    measures that outlet and the replay is on a cut. Their heat then reaches the storage as the
    lab's did, and the effects left to judge are those of the rest of the plant."""
    rp, rec = p.replayer, p.ctx.rec
    units = [u for u in rp.roles.ran if cut_mod.outlet_cuttable(rec, rp.house_name, u)]
    if rp.cut is None or not units:
        return {}
    modes = unit_modes.identify(rec, rp.run().rows, p.ctx.index, {u: rp.roles.ran[u] for u in units})
    public = unit_modes.public(modes)
    return {u: public[u] for u, m in modes.items() if unit_modes.run_otherwise(m)}


def calibrate(p: Prepared, house: str, refit_nominal: bool, log, jobs: int | None = 1) -> Baseline:
    """The subsystems replayed alone calibrated on their own interfaces, the unit modes the twin
    lacks masked, then the nominal re-fit (calibration.knobs, narrow bounds; its
    identifiability's replays in up to `jobs` processes)."""
    ctx, rp = p.ctx, p.replayer
    emitter = rp.calibrate_emitter(ctx.train)
    calibrated = ()
    hc = rp.heating
    if emitter and emitter["calibrated"]:
        rp = rp.with_calibration(emitter["values"], {hc.emitter}, emitter["elements"])
        calibrated = hc.emitter_outputs
        log(f"{hc.noun} alone: {emitter['elements']} element(s), " + ", ".join(
            f"{k} {v:.4g}" for k, v in emitter["values"].items()) + f", return RMS {emitter['rms_K']:.3g} K")
    mixer = rp.calibrate_mixer(ctx.train)
    if mixer and mixer["calibrated"]:
        rp = rp.with_calibration(mixer["values"])
        log("mixing station alone: " + ", ".join(f"{k} {v:.4g}" for k, v in mixer["values"].items())
            + f", supply RMS {mixer['rms_file_K']:.3g} -> {mixer['rms_K']:.3g} K")
    first = rp.run()
    warnings = list(p.warnings) + rp.notes + rp.boundary_check(first.rows)
    # a unit's own modes the twin lacks (a boiler's lock-out) are not scored (unit_modes.py)
    modes = unit_modes.identify(ctx.rec, first.rows, ctx.index, rp.roles.ran)
    ctx = unit_modes.apply(ctx, modes)
    nref, ranges, nominal = {"parameters": [], "params": []}, {}, first
    if refit_nominal:
        nref = calibration.refit_nominal(ctx, rp, house, jobs=jobs)
        rp = rp.with_calibration(nref["overrides"])
        ranges = calibration.ranges(nref)
        nominal = rp.run()
        sim_file = first.rows[:, ctx.cols]
        nref = {**nref, "train_cost_file": ctx.cost(sim_file, ctx.train),
                "heldout_cost_file": ctx.cost(sim_file, ctx.held)}
        if nref.get("storage_scheme"):
            log(f"storage scheme: {nref['storage_scheme']['chosen']}")
        log("nominal re-fit: " + ", ".join(f"{q['name']} {q['file_value']:.4g} -> {q['fitted_value']:.4g}"
                                           for q in nref["parameters"]))
    # what each pipe sensor reads while its branch stands, as the nominal replay found it: a later
    # replay reads the twin's own stagnant fluid only where the nominal does (pipe_sensor.py)
    rp = rp.with_calibration(pipe_nominal=nominal.pipe)
    # the subsystems replayed alone between measured interfaces: candidates on them are judged there
    alone = ((({"instances": {hc.station}, "signals": list(hc.station_outputs)},) if rp.circuit else ())
             + (({"instances": {hc.emitter}, "signals": list(hc.emitter_outputs)},) if rp.emitter else ()))
    ctx = ctx.with_baseline(nominal, alone, calibrated, ranges, rp.base)
    ctx = replace(ctx, unrepresented=unrepresented.find(ctx, ctx.nominal_sim))
    J0t, J0h = ctx.cost(ctx.nominal_sim, ctx.train), ctx.cost(ctx.nominal_sim, ctx.held)
    log(f"nominal replay: training cost {J0t:.4g}, held-out cost {J0h:.4g} "
        f"({len(ctx.measured)} measured signals)")
    return Baseline(ctx, rp, nominal, nref, emitter, mixer, modes, tuple(warnings), J0t, J0h)


def locate_mismatch(b: Baseline) -> Location:
    ctx, rp, sim0 = b.ctx, b.replayer, b.ctx.nominal_sim
    affected = locate.mismatched_signals(ctx, sim0, ctx.held)
    summary = {"replay": {"plant": rp.plant_label, "cut": rp.cut.name if rp.cut else None,
                          "generators_at_measured_outlet": list(outlets_of(rp)),
                          "boundaries": dict(rp.bound), "mixing_station_alone": rp.circuit,
                          "emitter_alone": rp.emitter},
               "subsystems": locate.subsystems(ctx, sim0, ctx.held, affected),
               "windows": locate.windows(ctx, sim0), "modes": locate.modes(ctx, sim0)[:6],
               "mismatched_signals": affected}
    return Location(tuple(affected), summary)


def fit_candidates(b: Baseline, effects, jobs: int | None, log) -> tuple:
    """Every candidate fitted on the training window (simulate-kind ones in parallel processes:
    each is independent); an implausible one comes back unfitted with its reason."""
    ctx, rp = b.ctx, b.replayer
    results, todo = [], []
    present = set(load(rp.house_name).instances)
    for e in (effects if effects is not None else catalogue(rp.house_name)):
        # a plant effect written for an instance this house lacks (a signal effect's component,
        # "sensor", is whichever sensor it is fitted on)
        if e.kind == "simulate" and e.component and e.component not in present:
            results.append(fit.Result(e.id, e.component, e.kind, False,
                                      f"{rp.house_name} has no {e.component}", effect=e))
            continue
        # a unit's own candidate on a unit the cut replaced (unless replayed alone: the heating
        # circuit's station and emitter, emitter.of)
        if isinstance(e, UnitEffect) and e.at in (rp.removed - rp.alone_instances) | set(outlets_of(rp)):
            results.append(fit.Result(e.id, e.component, e.kind, False, f"the replay's cut puts measurements where "
                                      f"{e.component} was, or runs it at its measured outlet ({rp.plant_label})",
                                      effect=e))
            continue
        ok, why = e.plausible(ctx) if e.available else (False, e.description)
        if not ok:
            results.append(fit.Result(e.id, e.component, e.kind, False, why, effect=e))
        else:
            results.append(None)
            todo.append((len(results) - 1, e))
    sims = [(i, e) for i, e in todo if e.kind == "simulate"]
    for (i, e), r in zip(sims, parallel.fit_all([e for _, e in sims], ctx, rp, b.train_cost,
                                                b.refit["params"], jobs)):
        results[i] = r
    for i, e in todo:
        if e.kind != "simulate":
            results[i] = fit.fit_signal(e, ctx, ctx.nominal_sim, rp)
    for i, e in todo:
        r = results[i]
        log(f"  {e.id:<20} {r.signal or '':<24} theta {r.theta[0] if r.theta else float('nan'):.4g}  "
            f"held-out cost {r.held_cost:.4g}")
    return tuple(results)


def select(b: Baseline, loc: Location, results: tuple) -> Selection:
    """Judge the candidates on the held-out window, reach the verdict, add further effects on top
    of the named one (forward.py), and search regression terms for what stays unexplained."""
    ctx = b.ctx
    judged = verdict_mod.judge(results, ctx, b.train_cost, b.held_cost)
    em = b.emitter or {}
    pinned = b.replayer.heating.emitter_outputs if em.get("calibrated") and em.get("at_bound") else ()
    verdict, best, twins, explained, judged = verdict_mod.select(judged, ctx, ctx.nominal_sim, list(loc.affected),
                                                                 pinned)
    chosen = forward.extend(best, judged, twins, ctx, b.replayer) if verdict == "missing_physics" else []
    # the report's "after": the model that holds every chosen effect (the best alone when only it)
    final = forward.final(chosen) if len(chosen) > 1 else best
    terms = search.search(ctx, b.nominal.rows, list(loc.affected)) if verdict != "no_missing_physics" else []
    return Selection(tuple(judged), verdict, best, tuple(twins), explained, tuple(chosen), final, tuple(terms))


def build_report(b: Baseline, loc: Location, s: Selection, house: str) -> dict:
    ctx, rp = b.ctx, b.replayer
    rep = report_mod.build(ctx, house, b.nominal.rows, ctx.nominal_sim, list(s.results), s.verdict, s.final,
                           list(s.twins), s.explained, loc.summary, list(s.terms), list(b.warnings))
    rep["nominal_refit"] = report_mod.nominal_refit(b.refit, ctx, ctx.nominal_sim, s.best)
    rep["effects"] = forward.public(list(s.chosen), ctx)
    if len(s.chosen) > 1:
        rep["finding"] += "; together with " + ", ".join(
            f"{r.id} ({r.effect.summary(r.theta, ctx, r.rows)}{' on ' + r.signal if r.signal else ''}, held-out "
            f"gain {100 * r.held_gain:.0f} % over the model before it)" for r in s.chosen[1:])
    rep["emitter_calibration"] = b.emitter
    rep["mixer_calibration"] = b.mixer
    # the nominal twin's fits, and the named model's where a plant effect changed its flows
    named = s.final.pipe if s.final is not None else {}
    rep["pipe_sensors"] = {flow: {**pipe_sensor.public(f), "T_plant_room_degC": rp.room.T,
                                  "T_plant_room_from": rp.room.source,
                                  "named_model": pipe_sensor.public(named[flow]) if flow in named else None}
                           for flow, f in b.nominal.pipe.items()}
    rep["unit_modes"] = unit_modes.public(b.modes)
    rep["unrepresented_sensors"] = ctx.unrepresented
    # in the catalogue's order: the fit keeps them in a set's, which differs between runs
    rep["storage_sensor_places"] = {sig: h.public(rp.heights[sig.rpartition(".T_sensor_")[0]].height)
                                    for sig, h in sorted(b.nominal.heights.items(),
                                                         key=lambda kv: rp.roles.catalogue.index(kv[0]))}
    report_mod.flag_bounds(rep, list(s.results))
    return rep


def diagnose(rec, house: str = "house1", out=None, train_days: float = 2.0, effects=None,
             plots: bool = True, log=print, refit_nominal: bool = True, jobs: int | None = None,
             require_cut: bool = False) -> dict:
    """The diagnosis of recording `rec` against `house` -> report.json's content (written to `out`
    with the plots when given). jobs: processes for the candidate fits and the calibration's
    identifiability replays (default: the CPUs this process may use); require_cut: refuse a
    recording that allows no cut (cut.select)."""
    timing = {}
    t0 = time.perf_counter()
    p = prepare(rec, house, train_days, require_cut)
    cut_at = outlets(p)
    if cut_at:
        log("replayed from their measured outlets: " + ", ".join(cut_at))
        p = prepare(rec, house, train_days, require_cut, cut_at)
    base = calibrate(p, house, refit_nominal, log, jobs)
    timing["replay_nominal"] = time.perf_counter() - t0
    t = time.perf_counter()
    loc = locate_mismatch(base)
    timing["locate"] = time.perf_counter() - t
    t = time.perf_counter()
    results = fit_candidates(base, effects, jobs, log)
    timing["fit"] = time.perf_counter() - t
    t = time.perf_counter()
    sel = select(base, loc, results)
    timing["select"] = time.perf_counter() - t
    t = time.perf_counter()
    rep = build_report(base, loc, sel, house)
    if out is not None:
        report_mod.write(rep, out, base.ctx, base.nominal.rows, sel.final, plots=plots)
    timing["report"] = time.perf_counter() - t
    timing["total"] = time.perf_counter() - t0
    rep["timing_s"] = timing
    if out is not None:
        report_mod.write_json(rep, out)
    return rep


__all__ = ["diagnose", "prepare", "outlets", "calibrate", "locate_mismatch", "fit_candidates", "select", "build_report",
           "Prepared", "Baseline", "Location", "Selection"]
