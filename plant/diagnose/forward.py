"""Forward selection: more than one effect when the data call for it.

After the best candidate is named, every other candidate is tried again on top of the model that
already holds the chosen effects, and judged by the same rules (verdict.judge) against that model
instead of the nominal twin: held-out gain >= MIN_GAIN (or, for a sensor candidate judged on its
own residual, LOCAL_GAIN of it), a better BIC and no parameter on a bound. The best accepted one
joins, and the search repeats (at most MAX_EFFECTS effects). How a candidate goes on top:
  * a sensor candidate is re-fitted on the current model's reading of each signal (fit.fit_signal,
    without a second joint radiator fit);
  * a plant candidate with a sensor effect chosen: its own fitted replay, with the chosen sensor's
    column taken from the current model (the sensor effect explains that reading, the plant
    candidate the rest);
  * a plant candidate on top of a plant effect: one replay with both sets of overrides at their
    fitted values (no re-fit: the first effect's fit already absorbed what it could).
A candidate on the same signal or component as a chosen one, or indistinguishable from it, is not
tried: it would explain the same residual twice. When a plant effect joins, the sensor effects
chosen before it are fitted again on its reading, each on its own signal: fitted on the nominal
twin, a sensor effect takes up what the plant effect does to its sensor (labsim
pair_idle_flow_lag: the top sensor's 600 s lag fitted as 727 s alone). `effects` reports those
joint values (`refitted_with`), and the report's headline (parameters, "after") is the model that
holds every chosen effect (`final`).
"""
from __future__ import annotations

import dataclasses

from . import fit
from . import verdict as verdict_mod

MAX_EFFECTS = 3


def _based_on(ctx, sim):
    """The context with `sim` as the model a candidate is judged against."""
    return dataclasses.replace(ctx, nominal_sim=sim)


def _on_top(r, current, chosen, ctx, replayer):
    """Candidate r evaluated on top of the current model (sim `current`); None if it cannot be."""
    base = _based_on(ctx, current)
    if r.kind == "signal":
        # on the radiator's return the first fit already re-fitted the radiator with the
        # candidate: here it is judged on the current model's reading (no second joint fit)
        return fit.fit_signal(r.effect, base, current)
    sensors = [c for c in chosen if c.kind == "signal"]
    plants = [c for c in chosen if c.kind == "simulate"]
    if plants:
        ov = {}
        for c in plants:
            ov.update(c.nominal)
            ov.update(c.effect.overrides(c.theta))
        own = r.effect.overrides(r.theta)
        if set(own) & {k for c in plants for k in c.effect.overrides(c.theta)}:
            return None
        ov.update(own)
        run = replayer.run(ov)
        rows, sim, pipe = run.rows, run.rows[:, ctx.cols], dict(run.pipe)
    else:
        rows, sim, pipe = r.rows, r.sim.copy(), r.pipe
    for c in sensors:
        j = ctx.measured.index(c.signal)
        sim[:, j] = current[:, j]
    return fit.Result(r.id, r.component, r.kind, True, theta=list(r.theta), stderr=list(r.stderr),
                      train_cost=ctx.cost(sim, ctx.train), held_cost=ctx.cost(sim, ctx.held),
                      evaluations=1, sim=sim, rows=rows, effect=r.effect, nominal=dict(r.nominal), pipe=pipe, k=r.k)


def extend(best, results, twins, ctx, replayer) -> list:
    """[best, further effects ...] (fit.Result each, with held_gain relative to the model before it)."""
    chosen = [best]
    current = best.sim
    tried = {r.id for r in chosen} | set(twins)
    while len(chosen) < MAX_EFFECTS:
        taken = {c.signal or c.component for c in chosen}
        trial = []
        for r in results:
            if r.id in tried or not r.plausible or r.sim is None or (r.signal or r.component) in taken:
                continue
            r2 = _on_top(r, current, chosen, ctx, replayer)
            if r2 is None or (r2.signal or r2.component) in taken:
                continue
            trial.append(r2)
        base = _based_on(ctx, current)
        held = ctx.cost(current, ctx.held)
        trial = verdict_mod.judge(trial, base, ctx.cost(current, ctx.train), held)
        acc = verdict_mod.ranked([r for r in trial if r.accepted], held)
        if not acc:
            break
        nxt = acc[0]
        if nxt.kind == "simulate" and nxt.rows is not None:
            chosen, nxt = _refit_sensors(chosen, nxt, ctx)
        chosen.append(nxt)
        tried.add(nxt.id)
        current = nxt.sim
    return chosen


def _refit_sensors(chosen, plant, ctx) -> list:
    """The chosen sensor effects fitted again on the reading of the model with `plant` joined
    (its replay's measured columns), each on its own signal. -> (chosen with the sensor effects
    replaced by their re-fitted copies, plant with their columns in its sim)."""
    sim = plant.rows[:, ctx.cols].copy()
    out = []
    for c in chosen:
        if c.kind != "signal":
            out.append(c)
            continue
        r = fit.fit_signal(c.effect, _based_on(ctx, sim), sim, only=c.signal)
        if not r.plausible:
            out.append(c)
            continue
        j = ctx.measured.index(c.signal)
        sim[:, j] = r.sim[:, j]
        out.append(dataclasses.replace(c, theta=r.theta, stderr=r.stderr, sim=sim, refitted_with=plant.id))
    return out, dataclasses.replace(plant, sim=sim)


def final(chosen):
    """The diagnosed model as one Result: the named effect with its values in the model that
    holds every chosen effect (fitted again when a plant effect joined), that model's simulation,
    and the rows and pipe-sensor fits of its last plant replay (None and {}: sensor effects only,
    the heat flows are the nominal's)."""
    last = next((c for c in reversed(chosen) if c.kind == "simulate" and c.rows is not None), None)
    return dataclasses.replace(chosen[0], sim=chosen[-1].sim, rows=last.rows if last is not None else None,
                               pipe=last.pipe if last is not None else {})


def public(chosen, ctx) -> list[dict]:
    """report.json `effects`: each chosen effect, what it adds over the model before it."""
    out = []
    for i, r in enumerate(chosen):
        p = r.public()
        out.append({"effect": r.id, "component": r.signal or r.component, "parameters": p["parameters"],
                    "summary": r.effect.summary(r.theta, ctx, r.rows),
                    "heldout_gain_over_previous": r.held_gain, "reason": r.reason,
                    "order": i + 1, "refitted_with": r.refitted_with})
    return out
