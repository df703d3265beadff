"""The building's heating controller: supply-temperature request and a PI room thermostat.

Supply temperature: constant (the original house: 60 degC) or a weather-compensated heating
curve T_sup = T_room_set + slope x (T_room_set - T_out) + offset, clamped to [T_min, T_max].
Flow: a PI controller on the room temperature error drives the circuit flow between 0 and the
pump maximum (the original's fast on/off thermostat with a 0.01 K band replaced by PI, as the
reference suggests, so that the flow is smooth and steps of 1-60 s behave alike).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, indices, link, pack, param

STATES = ("integral",)


@dataclass(frozen=True)
class Params:
    curve: bool = param(False, "-", "true: weather-compensated heating curve; false: constant supply")
    T_sup_constant: float = param(60.0, "degC", "supply temperature request without heating curve", 20, 95)
    slope: float = param(1.2, "1", "heating-curve slope", 0.1, 4)
    offset: float = param(0.0, "K", "heating-curve parallel shift", -20, 20)
    T_sup_min: float = param(30.0, "degC", "heating-curve minimum", 15, 95)
    T_sup_max: float = param(70.0, "degC", "heating-curve maximum", 15, 95)
    m_flow_max: float = param(0.25, "kg/s", "flow at full demand", 0.001, 10)
    K_p: float = param(1.0, "1/K", "proportional gain (share of maximum flow per K)", 0, 100)
    T_i: float = param(1800.0, "s", "integral time", 10, 1e6)


# positions in the packed parameter vector, from the declaration
P = indices(Params)


def initial_state(params: Params) -> np.ndarray:
    return np.zeros(1, dtype=np.float64)


@njit(cache=True)
def step(dt, x, p, T_room, T_room_set, T_out):
    """Returns (T_sup_set [degC], m_flow_set [kg/s])."""
    if p[P.curve] > 0.5:
        T_sup = T_room_set + p[P.slope] * (T_room_set - T_out) + p[P.offset]
        T_sup = min(max(T_sup, p[P.T_sup_min]), p[P.T_sup_max])
    else:
        T_sup = p[P.T_sup_constant]
    e = T_room_set - T_room
    u = p[P.K_p] * e + x[0]
    if 0.0 < u < 1.0 or (u <= 0.0 and e > 0.0) or (u >= 1.0 and e < 0.0):
        x[0] += dt * p[P.K_p] * e / p[P.T_i]  # conditional integration: no wind-up at the limits
    u = min(max(u, 0.0), 1.0)
    return T_sup, u * p[P.m_flow_max]


class Kind(ComponentKind):
    """Room thermostat: room temperature, its set-point and the outdoor air in; the heating
    circuit's supply set-point and flow out."""

    name = "room_thermostat"
    Params = Params
    role = "controller"
    INPUTS = ("T_room", "T_room_set", "T_out")
    OUTPUTS = ("T_sup_set", "m_flow_set")
    LINKS = {"inputs": link(REQUIRED, "T_room, T_room_set, T_out = signal names", type=dict),
             "outputs": link(REQUIRED, "T_sup_set, m_flow_set = input signal names", type=dict)}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit(self, c, inst):
        from . import check_keys, read, write

        check_keys(c, inst, self.INPUTS, self.OUTPUTS)
        x, p = c.state(inst, self.initial_state(inst)), c.param(inst, pack(inst.params))
        T_sup, m = c.var("T_sup_req"), c.var("m_req")
        mod = c.module(__name__)
        c.emit("control", f"{T_sup}, {m} = {mod}.step(h, {x}, {p}, "
                          f"{', '.join(read(c, inst, k) for k in self.INPUTS)})")
        write(c, inst, "T_sup_set", T_sup)
        write(c, inst, "m_flow_set", m)
