"""A well-mixed water volume with heat loss: the supply and return headers of the hydraulic switch.

The headers give the coupling point its (small) water content, which also breaks the algebraic
loop between generators and consumers: everything that leaves a header in a step leaves at the
header's start-of-step temperature, so the energy ledger closes exactly. Explicit update, stable
while dt x (inflow) < volume mass; the house splits longer steps (plant/schedule.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, indices, param
from ..water import CP, RHO

STATES = ("T",)


@dataclass(frozen=True)
class Params:
    V: float = param(0.010, "m3", "water content (header and connecting pipes)", 0.0005, 1)
    UA_loss: float = param(1.0, "W/K", "heat loss coefficient to the surroundings", 0, 100)
    T_env: float = param(18.0, "degC", "surroundings (plant room) temperature", -20, 40)
    T_init: float = param(50.0, "degC", "initial water temperature", 0, 95)


# positions in the packed parameter vector, from the declaration
P = indices(Params)


def initial_state(params: Params) -> np.ndarray:
    return np.array([params.T_init], dtype=np.float64)


@njit(cache=True)
def step(dt, x, p, H_in, m_in):
    """H_in: enthalpy inflow sum(m_i cp T_i) [W], m_in: total inflow [kg/s] (= outflow).

    Returns the heat loss [W]. The outflow leaves at the start-of-step temperature x[0].
    """
    T = x[0]
    Q_loss = p[P.UA_loss] * (T - p[P.T_env])
    x[0] = T + dt * (H_in - m_in * CP * T - Q_loss) / (CP * RHO * p[P.V])
    return Q_loss


class Kind(ComponentKind):
    """A mixed volume (a header and its connecting pipes); stepped by the coupling point that
    uses it as its supply or return."""

    name = "header"
    Params = Params
    role = "volume"

    def initial_state(self, inst):
        return initial_state(inst.params)

    def stored_energy(self, inst, x):
        return CP * RHO * inst.params.V * float(x[0])

    def views(self, c, inst):
        """The state and parameter views (allocated by the first coupling point that uses the
        header)."""
        return c.views(inst)
