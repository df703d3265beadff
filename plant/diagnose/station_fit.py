"""A candidate on the mixing station replayed alone, fitted jointly with the station's own
calibration (its actuator's running time and its controller's integral gain: cut.calibrate_mixer).

Calibrated before any candidate, the station's two parameters take part of what a candidate on
it would explain: on rigsim r1's valve_leak_8 the actuator came out 143 s for the rig's 89 s and
the integral gain 34 x the file's, and the 8 % seat leak was fitted as 0.035, removing 25 % of
the station's residual (under fit.LOCAL_GAIN); with the station left at its file values, 0.050
and 35 %. So each value the search tries takes the station's best calibration for it, on the
samples that calibration uses, as a sensor candidate on the emitter's return takes the
emitter's (fit._try_signal); the pair is then replayed once over the whole recording.
"""
from __future__ import annotations

from .bounded import scalar_search
from .sim_fit import stderr


def applies(effect, replayer) -> bool:
    """Whether `effect` (one parameter, kind simulate) sets only the mixing station that the
    replay runs alone and has calibrated."""
    if not replayer.circuit or len(effect.params) != 1:
        return False
    station = replayer.heating.station
    keys = effect.overrides([effect.params[0].nominal])
    calibrated = any(k.startswith(f"{station}.") for k in replayer.base)
    return calibrated and bool(keys) and all(k.split(".", 1)[0] == station for k in keys)


def fit(effect, ctx, replayer):
    """The candidate's value by a bounded search on the station's calibrated training cost at
    each value -> fit.Result (its `nominal`: the station's calibration at the fitted value)."""
    from .fit import Result

    p, calibrations = effect.params[0], {}

    def calibrated(v):
        key = round(float(v), 9)
        if key not in calibrations:
            calibrations[key] = replayer.calibrate_mixer(ctx.train, effect.overrides([key]))
        return calibrations[key]

    def cost(v):
        return calibrated(v)["rms_K"] ** 2

    v, J, _ = scalar_search(cost, p, n_grid=5, maxiter=8)
    station = calibrated(v)["values"]
    run = replayer.run({**station, **effect.overrides([v])})
    sim = run.rows[:, ctx.cols]
    return Result(effect.id, effect.component, effect.kind, True, theta=[v],
                  stderr=[stderr(cost, p, v, J, ctx.n_eff(ctx.train))],
                  train_cost=ctx.cost(sim, ctx.train), held_cost=ctx.cost(sim, ctx.held),
                  evaluations=len(calibrations) + 1, sim=sim, rows=run.rows, effect=effect,
                  nominal=dict(station), pipe=dict(run.pipe),
                  fit_note="fitted with the mixing station calibrated again at each value (station_fit.py)")
