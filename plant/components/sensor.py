"""A sensor effect on any signal (`kind = "sensor"`): what a real thermometer or meter reports
instead of the model's exact value. Declared like a component, so diagnosis and users add it to
a house the same way:

    [chp_outlet_sensor]
    kind = "sensor"
    signal = "chp.T_sup"          # the signal the sensor reports (overwritten in place)
    lag = 60.0                    # s, first-order time constant (0: none)
    offset = 0.3                  # K (or the signal's unit), added to what it reads
    stagnant_flow = "chp.m_flow"  # optional: below stagnant_below the pipe stands still and
    stagnant_below = 1e-4         #   the sensor cools toward T_env with tau_stagnant
    T_env = 18.0
    tau_stagnant = 1800.0

Physics in words: a sensor in a thermowell follows its fluid with a first-order lag; on a pipe
without flow it no longer sees the generator's water but the pipe cooling toward the room
(first-order with the pipe's time constant). The offset is a calibration error. The filter runs
on the end-of-step value and is applied again at the next step's start, so built-in controllers
read what the sensor reports, as a PLC would.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, SignalName, indices, link, pack, param


@dataclass(frozen=True)
class Params:
    lag: float = param(0.0, "s", "first-order time constant (0: none)", 0.0, 1e5)
    offset: float = param(0.0, "1", "added to the reading, in the signal's unit", -100.0, 100.0)
    stagnant_below: float = param(1e-4, "kg/s", "flow below which the pipe stands still", 0.0, 10.0)
    T_env: float = param(18.0, "degC", "surroundings the stagnant pipe cools toward", -30.0, 60.0)
    tau_stagnant: float = param(1800.0, "s", "time constant of the stagnant pipe", 1.0, 1e6)


STATES = ("value",)  # the lagged reading, before the offset
# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


@njit(cache=True)
def read(s, i, flow, x, p, h, update):
    """Replace s[i] by the sensor's reading (flow < 0: no stagnant-pipe behaviour)."""
    raw = s[i]
    if not math.isfinite(x[X.value]):
        x[X.value] = raw
    if update:
        if 0.0 <= flow < p[P.stagnant_below]:
            x[X.value] += -math.expm1(-h / p[P.tau_stagnant]) * (p[P.T_env] - x[X.value])
        elif p[P.lag] > 0.0:
            x[X.value] += -math.expm1(-h / p[P.lag]) * (raw - x[X.value])
        else:
            x[X.value] = raw
    s[i] = x[X.value] + p[P.offset]


class Kind(ComponentKind):
    name = "sensor"
    Params = Params
    role = "sensor"
    LINKS = {"signal": link(REQUIRED, "the signal the sensor reports", type=SignalName),
             "stagnant_flow": link(None, "a flow signal: below stagnant_below the pipe stands still", type=SignalName)}

    def emit(self, c, inst):
        sig, flow = inst.options["signal"], inst.options["stagnant_flow"]
        x = c.state(inst, np.full(len(STATES), np.nan))
        p = c.param(inst, pack(inst.params))
        mod = c.module(__name__)
        f = c.s(flow) if flow else "-1.0"
        c.emit("sense", f"{mod}.read(s, {c.s(sig)[2:-1]}, {f}, {x}, {p}, h, False)")
        c.emit("signals", f"{mod}.read(s, {c.s(sig)[2:-1]}, {f}, {x}, {p}, h, True)")
