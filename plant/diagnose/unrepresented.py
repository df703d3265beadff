"""Storage sensors the twin cannot represent, found and reported rather than explained.

A tank sensor at a port, or in the plume of an inflow, reads the port's water while that port
flows and the tank's layer while it stands. The twin's layers resolve neither: relative to its
neighbours (fit.common_mode) such a sensor's residual changes sign with the operating state, as
no offset, lag or tank-wide effect can make it do. rigsim house 2's sensor 2, at the heat
pump's lower return port, read +2.8 K against the twin with the heat pump on and -3.0 K with it
off, in every case of the suite, the no-effect ones included.

Such a sensor is reported (report.json `unrepresented_sensors`) with what it reads in each
state, found once on the nominal replay (Context.unrepresented), and no effect that reads the
same in every state (an offset: Effect.same_in_every_state) is named on it (fit._unlike): one
value cannot be the error of a reading that takes both signs. The offset's own shape check in
every state (SensorOffset.unlike) is weaker where the sensor's place is fitted with the offset:
rigsim house 2's null_a named +5.15 K on sensor 2 through it. A lag, whose residual changes sign
with the tank's rise and fall, may still be named on such a sensor (labsim's and rigsim's lagging
top sensors are listed here). The limit is the one mismatch limit of the signal
(Context.limit): a state mean beyond it, with either sign, in states that each
cover at least STATE_SHARE of the recording (the sensor offset's own, effects/sensor.py), both
relative to its neighbours and of its own reading (a neighbour's relative residual mirrors it).
"""
from __future__ import annotations

import numpy as np

from .effects.sensor import STATE_SHARE
from .fit import common_mode


def find(ctx, sim: np.ndarray) -> dict:
    """{storage sensor: {"state_means_K": {state: mean relative residual}, "limit_K", "why"}} of the
    measured storage sensors whose residual relative to their neighbours, in the replay `sim`
    (measured columns), is beyond their limit with one sign in one state and the other in another."""
    states = ctx.states
    out = {}
    for j, s in enumerate(ctx.measured):
        c = common_mode(ctx, sim, j)
        if c is None:
            continue
        n = len(c)
        ok = ctx.ok[:n, j]
        e = ctx.meas[:n, j] - sim[:n, j]
        use = {name: m[:n] & ok for name, m in states.items() if (m[:n] & ok).sum() >= STATE_SHARE * ok.sum() > 0}
        means = {name: float(np.mean(e[m] - c[m])) for name, m in use.items()}
        lim = float(ctx.limit(j))
        hi = max(means.items(), key=lambda kv: kv[1], default=(None, 0.0))
        lo = min(means.items(), key=lambda kv: kv[1], default=(None, 0.0))
        # its own reading, not only relative to its neighbours: a neighbour's relative residual
        # mirrors the sensor's (rigsim house 2's sensors 1 and 3 beside sensor 2, whose own
        # readings stayed within 0.5 K in every state)
        own = [float(np.mean(e[use[k]])) for k in (hi[0], lo[0]) if k is not None]
        if hi[1] > lim and lo[1] < -lim and own[0] > lim and own[1] < -lim:
            out[s] = {"state_means_K": {k: round(v, 3) for k, v in means.items()}, "limit_K": round(lim, 3),
                      "why": (f"relative to its neighbours it reads {hi[1]:+.1f} K with {hi[0].replace('_', ' ')} "
                              f"and {lo[1]:+.1f} K with {lo[0].replace('_', ' ')} (limit {lim:.2f} K): a sensor "
                              "at a port or in an inflow's plume, which the twin's layers do not resolve; no "
                              "offset is named on it")}
    return out


__all__ = ["find"]
