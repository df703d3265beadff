"""Radiator circuit of the living zone: one water node, emission from the log-mean temperature difference.

Physics (the original's equation, GreenCity `HeatingSystem`):
    C_w dT_ret/dt = m cp (T_sup - T_ret) - Q_N (LMTD / LMTD_N)^n,   LMTD = (b - a)/ln(b/a),
with a = T_ret - T_room, b = T_sup - T_room; with no flow the water cools towards the room
(emission from a = b). Explicit and exactly conservative: the water leaving carries the
start-of-step return temperature. Nominal point 60/45/21 degC, Q_N = 22 W/m2 x 2 floors x
199.5 m2 = 8.78 kW, exponent 1.3, water content 0.25 m3 (reference section 9.7).

| parameter | unit | meaning |
|---|---|---|
| Q_nominal | W | emission at the nominal temperatures |
| T_sup_nominal, T_ret_nominal, T_room_nominal | degC | nominal point |
| exponent | 1 | radiator exponent (1.3 radiators, 1.0-1.1 floor heating) |
| V_water | m3 | water content of radiators and pipes |
Validated by tests/plant/test_heating_circuit.py (nominal emission, cooling with no flow, energy).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Instance, Kind as ComponentKind, Knob, indices, link, param
from ..water import CP, RHO
from . import zone as zone_kind

STATES = ("T_ret",)


@dataclass(frozen=True)
class Params:
    Q_nominal: float = param(8778.0, "W", "emission at the nominal temperatures", 100, 1e6)
    T_sup_nominal: float = param(60.0, "degC", "nominal supply temperature", 20, 95)
    T_ret_nominal: float = param(45.0, "degC", "nominal return temperature", 15, 90)
    T_room_nominal: float = param(21.0, "degC", "nominal room temperature", 10, 30)
    exponent: float = param(1.3, "1", "radiator exponent", 1.0, 1.5)
    V_water: float = param(0.25, "m3", "water content of radiators and pipes", 0.001, 10)
    T_init: float = param(30.0, "degC", "initial water temperature", 0, 95)


# positions in the packed parameter vector, from the declaration
P = indices(Params)


def initial_state(params: Params) -> np.ndarray:
    return np.array([params.T_init], dtype=np.float64)


@njit(cache=True)
def lmtd(a, b):
    """Logarithmic mean of two positive over-temperatures (= a when a = b; 0 if either <= 0)."""
    if a <= 1e-6 or b <= 1e-6:
        return 0.0
    if abs(a - b) < 1e-6 * max(a, b):
        return 0.5 * (a + b)
    return (b - a) / math.log(b / a)


@njit(cache=True)
def step(dt, x, p, m_flow, T_sup, T_room):
    """Advance by dt; returns (T_ret_out leaving this step, Q_emitted to the room [W])."""
    T_ret = x[0]
    a = T_ret - T_room
    b = T_sup - T_room if m_flow > 0.0 else a
    if b < a:  # supply colder than the water inside: emission from the warmer end only
        b = a
    dT_n = lmtd(p[P.T_ret_nominal] - p[P.T_room_nominal], p[P.T_sup_nominal] - p[P.T_room_nominal])
    d = lmtd(a, b)
    Q = p[P.Q_nominal] * (d / dT_n) ** p[P.exponent] if d > 0.0 else 0.0
    C = CP * RHO * p[P.V_water]
    x[0] = T_ret + dt * (m_flow * CP * (T_sup - T_ret) - Q) / C
    return T_ret, Q


class Kind(ComponentKind):
    """Radiators as the emitter of a mixing station, giving their heat to a zone (link `zone`)."""

    name = "radiator"
    Params = Params
    role = "emitter"
    LINKS = {"zone": link(REQUIRED, "the zone the radiators heat", type=Instance, range=("zone",))}
    KNOBS = (Knob("Q_nominal", "W", "emitter size (rating, valve settings): with the mixer set-points "
                  "replayed it sets the heating return temperature, hence the storage bottom and the "
                  "coupling point's return", rel=0.10, rank=1),)

    def initial_state(self, inst):
        return initial_state(inst.params)

    def stored_energy(self, inst, x):
        return CP * RHO * inst.params.V_water * float(x[0])

    KERNEL = __name__   # the module whose step(dt, x, p, m_flow, T_sup, T_room) the emitter calls
    HEAT = "heat emitted by the radiators into the zone"

    def return_state(self, c, inst):
        """The start-of-step return temperature (the water node; allocated by the first of the
        mixing station and the emitter to ask)."""
        x, _ = c.views(inst)
        return f"{x}[0]"

    def emit_emitter(self, c, inst, m_flow, T_sup):
        x, p = c.views(inst)
        zone = c.instances[inst.options["zone"]]
        T_ret, Q = c.var(f"T_{inst.name}_ret"), c.var(f"Q_{inst.name}")
        mod = c.module(self.KERNEL)
        c.emit("hydraulics", f"{T_ret}, {Q} = {mod}.step(h, {x}, {p}, {m_flow}, {T_sup}, "
                             f"{c.state_of(inst, zone)}[{zone_kind.X.T_room}])")
        c.heat_to.setdefault(zone.name, []).append(Q)
        c.emit("signals", *self.extra_signals(c, inst),
               f"{c.signal(inst, 'Q_flow', 'W', 'output', self.HEAT)} = {Q}",
               f"{c.ledger_entry(inst, 'building')} += {Q} * h")
        return T_ret

    def extra_signals(self, c, inst) -> list[str]:
        return []
