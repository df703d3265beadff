"""Heating-circuit mixing station: 3-way mixing valve with finite actuator speed and a pump.

The pump delivers the requested building-side flow up to its maximum. The valve mixes primary
supply water (from the hydraulic switch) with the circuit's own return; its position y is the
primary share. The valve controller aims at the set supply temperature with a feed-forward
position y* = (T_set - T_ret)/(T_primary - T_ret), corrected by an integral term on the measured
supply temperature, and the actuator moves at most 1/t_stroke per second (a 3-point actuator).
Measured: building-side flow and supply temperature after mixing, primary (storage-side) flow.
Mass balance: primary flow in = primary flow out = y x m_flow; exact energy follows from mixing.

| parameter | unit | meaning |
|---|---|---|
| m_flow_max | kg/s | pump maximum (15 l/min) |
| t_stroke | s | actuator running time for a full stroke |
| K_i | 1/(K s) | integral gain of the supply-temperature correction |
| leak | 1 | primary share the closed valve still passes (seat leakage; 0 = tight) |

Leakage: the valve's primary share is leak + (1 - leak) y, so a closed valve (y = 0) still lets
`leak` of the circuit flow in from the primary side; the controller compensates while it can
(y > 0), so a leak shows when the valve should be closed (supply set-point at or below the
circuit return). leak = 0 is bit-identical to a tight valve.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Instance, Kind as ComponentKind, indices, link, pack, param

STATES = ("y", "y_integral")


@dataclass(frozen=True)
class Params:
    m_flow_max: float = param(0.25, "kg/s", "pump maximum flow (15 l/min)", 0.001, 10)
    t_stroke: float = param(120.0, "s", "valve actuator running time 0 -> 100 %", 1, 3600)
    K_i: float = param(2.0e-4, "1/(K s)", "integral gain on the supply-temperature error", 0, 1)
    leak: float = param(0.0, "1", "primary share the closed valve still passes (seat leakage)", 0.0, 0.5)


# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


def initial_state(params: Params) -> np.ndarray:
    return np.zeros(2, dtype=np.float64)


@njit(cache=True)
def step(dt, x, p, T_set, m_flow_set, T_primary, T_ret):
    """Move the valve for dt; returns (m_flow, m_flow_primary, T_sup after mixing, y)."""
    m = min(max(m_flow_set, 0.0), p[P.m_flow_max])
    y = p[P.leak] + (1.0 - p[P.leak]) * x[X.y]
    T_sup = y * T_primary + (1.0 - y) * T_ret
    if m > 0.0:
        span = T_primary - T_ret
        y_ff = (T_set - T_ret) / span if span > 0.1 else 1.0
        x[X.y_integral] = min(max(x[X.y_integral] + dt * p[P.K_i] * (T_set - T_sup), -0.3), 0.3)
        target = min(max(y_ff + x[X.y_integral], 0.0), 1.0)
        # the actuator position that gives the target share past the leak
        dy = max((target - p[P.leak]) / (1.0 - p[P.leak]), 0.0) - x[X.y]
        lim = dt / p[P.t_stroke]
        x[X.y] = x[X.y] + min(max(dy, -lim), lim)
    return m, y * m, T_sup, y


class Kind(ComponentKind):
    """The mixing station as a consumer of a coupling point: it draws primary water at the
    coupling point's supply temperature and feeds its emitter (link `emitter`)."""

    name = "mixing_station"
    Params = Params
    role = "consumer"
    LINKS = {"emitter": link(REQUIRED, "the emitter the station feeds (a radiator or floor heating)",
                             type=Instance, range=("emitter",))}
    RUN, PIPES = ("m_flow_set", 0.005), ("T_sup", "T_ret")
    SUBSTITUTES = {"m_flow_set": "m_flow", "T_sup_set": "T_sup"}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit_consumer(self, c, inst, T_sup):
        x, p = c.state(inst, self.initial_state(inst)), c.param(inst, pack(inst.params))
        emitter = c.instances[inst.options["emitter"]]
        m, m_prim, T_mix, y = (c.var(v) for v in ("m_mix", "m_prim", "T_mix", "y_valve"))
        T_set = c.signal(inst, "T_sup_set", "degC", "input", "heating-circuit supply temperature set-point")
        m_set = c.signal(inst, "m_flow_set", "kg/s", "input", "heating-circuit flow set-point")
        mod = c.module(__name__)
        T_emitter_ret = c.kinds[emitter.kind].return_state(c, emitter)
        c.emit("hydraulics", f"{m}, {m_prim}, {T_mix}, {y} = {mod}.step(h, {x}, {p}, {T_set}, {m_set}, "
                             f"{T_sup}, {T_emitter_ret})")
        T_ret = c.kinds[emitter.kind].emit_emitter(c, emitter, m, T_mix)
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('T_sup', 'degC', 'heating supply temperature after mixing (measured)')} = {T_mix}",
               f"{sig('T_ret', 'degC', 'heating return temperature')} = {T_ret}",
               f"{sig('m_flow', 'kg/s', 'heating-circuit flow (building side, measured)')} = {m}",
               f"{sig('m_flow_primary', 'kg/s', 'flow drawn from the coupling point (before mixing)')} = {m_prim}",
               f"{sig('y_valve', '1', 'mixing valve position (primary share)')} = {y}",
               f"{sig('Q_flow', 'W', 'heat taken from the coupling point by the heating circuit')} = "
               f"{m_prim} * CP * ({T_sup} - {T_ret})")
        return m_prim, T_ret
