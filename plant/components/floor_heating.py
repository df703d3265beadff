"""Floor heating of the living zone: water and screed as one node, emission from the log-mean temperature difference.

Physics (the radiator's equation, reference §9.7, with the screed's heat capacity added):
    (C_screed + cp·ρ·V_water)·dT_ret/dt = m·cp·(T_sup − T_ret) − Q_N·(LMTD/LMTD_N)^n,
    LMTD = (b − a)/ln(b/a),  a = T_ret − T_room,  b = T_sup − T_room,
with no flow the floor cools towards the room (emission from a = b). The nominal point is the
ProHMo houses' floor heating (§9.5, §12.3-12.4): 40/30 °C supply/return at 20 °C room, exponent 1.1
(EN 1264's characteristic); Q_N = 16 W/m² per floor × 2 floors × 199.5 m² = 6.38 kW (SF2, the
house-1-sized building). Explicit and exactly conservative: the water leaving carries the
start-of-step return temperature, the node's energy changes by what flows in minus the emission.

A trickle: the LMTD law assumes the water leaves at the node temperature, which a small flow
into a large floor does not do (it gives its heat up near the manifold); so the emission is at
most the node's own emission (a = b) plus what the water brings in, m·cp·(T_sup − T_ret). In
steady state the bound is inactive (emission = m·cp·(T_sup − T_ret)), so the characteristic holds.

Assumptions: the screed follows the water temperature (one node: the pipes sit in the screed and
the emission law is applied from that node, so the steady state is EN 1264's characteristic
exactly); the heat the screed gives downwards (to the slab and cellar) is counted as emission into
the zone. The screed default is a 45 mm cement screed over 300 m² of heated floor (2000 kg/m³,
1000 J/(kg K): 2.7·10⁷ J/K); the water content 1.2 l/m² of 16 mm pipe at 10 cm spacing. The time
constant is then C/(Q_N/LMTD_N) ≈ 18 h at the nominal point.

| parameter | unit | meaning |
|---|---|---|
| Q_nominal | W | emission at the nominal temperatures |
| T_sup_nominal, T_ret_nominal, T_room_nominal | degC | nominal point |
| exponent | 1 | emission exponent (EN 1264: 1.0-1.1) |
| V_water | m3 | water content of the floor circuits |
| C_screed | J/K | heat capacity of the screed around the pipes |
| T_init | degC | initial water and screed temperature |

Validated by tests/plant/test_floor_heating.py (nominal emission, exponent law at part load,
cooling with no flow, energy balance in a house).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Instance, indices, link, param
from ..water import CP, RHO
from . import radiator
from .radiator import lmtd

STATES = ("T_ret",)


@dataclass(frozen=True)
class Params:
    Q_nominal: float = param(6384.0, "W", "emission at the nominal temperatures", 100, 1e6)
    T_sup_nominal: float = param(40.0, "degC", "nominal supply temperature", 20, 60)
    T_ret_nominal: float = param(30.0, "degC", "nominal return temperature", 15, 55)
    T_room_nominal: float = param(20.0, "degC", "nominal room temperature", 10, 30)
    exponent: float = param(1.1, "1", "emission exponent", 1.0, 1.5)
    V_water: float = param(0.36, "m3", "water content of the floor circuits", 0.001, 10)
    C_screed: float = param(2.7e7, "J/K", "heat capacity of the screed around the pipes", 0.0, 1e10)
    T_init: float = param(25.0, "degC", "initial water and screed temperature", 0, 60)


# positions in the packed parameter vector, from the declaration
P = indices(Params)


def initial_state(params: Params) -> np.ndarray:
    return np.array([params.T_init], dtype=np.float64)


def capacity(params: Params) -> float:
    """Heat capacity of water and screed [J/K]."""
    return CP * RHO * params.V_water + params.C_screed


@njit(cache=True)
def emission(p, T_ret, T_sup, m_flow, T_room):
    """Heat given to the room [W] by a floor at T_ret fed with m_flow at T_sup."""
    a = T_ret - T_room
    b = T_sup - T_room if m_flow > 0.0 else a
    if b < a:  # supply colder than the floor: emission from the warmer end only
        b = a
    dT_n = lmtd(p[P.T_ret_nominal] - p[P.T_room_nominal], p[P.T_sup_nominal] - p[P.T_room_nominal])
    d = lmtd(a, b)
    Q = p[P.Q_nominal] * (d / dT_n) ** p[P.exponent] if d > 0.0 else 0.0
    if b > a:  # a trickle cannot warm the whole floor: the node's own emission plus what flows in
        own = p[P.Q_nominal] * (lmtd(a, a) / dT_n) ** p[P.exponent] if a > 0.0 else 0.0
        Q = min(Q, own + m_flow * CP * (T_sup - T_ret))
    return Q


@njit(cache=True)
def step(dt, x, p, m_flow, T_sup, T_room):
    """Advance by dt; returns (T_ret leaving this step, Q emitted to the room [W])."""
    T_ret = x[0]
    Q = emission(p, T_ret, T_sup, m_flow, T_room)
    C = CP * RHO * p[P.V_water] + p[P.C_screed]
    x[0] = T_ret + dt * (m_flow * CP * (T_sup - T_ret) - Q) / C
    return T_ret, Q


class Kind(radiator.Kind):
    """Floor heating as the emitter of a mixing station, giving its heat to a zone (link `zone`)."""

    name = "floor_heating"
    Params = Params
    role = "emitter"
    LINKS = {"zone": link(REQUIRED, "the zone the floor heats", type=Instance, range=("zone",))}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def stored_energy(self, inst, x):
        return capacity(inst.params) * float(x[0])

    KERNEL = __name__
    HEAT = "heat emitted by the floor into the zone"

    def extra_signals(self, c, inst):
        return [f"{c.signal(inst, 'T_floor', 'degC', 'output', 'water and screed temperature (the return)')} = "
                f"{self.return_state(c, inst)}"]
