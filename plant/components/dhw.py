"""Domestic hot-water draw with a thermostatic mixing valve at the tap.

The draw profile gives the flow of mixed water at the set temperature (45 degC). The mixing valve
takes just enough hot water from the top of the DHW storage to reach the set temperature:
    m_hot = m_demand (T_set - T_cold)/(T_hot - T_cold)      if T_hot >= T_set,
otherwise all of the draw is hot water and it arrives too cold (a service failure; the missing
heat is reported). The same mass of cold water enters the storage bottom. Heat delivered to the
tap = m_hot cp (T_hot - T_cold) (reference section 10.1, with T_tol folded into the failure rule).
"""
from __future__ import annotations

from dataclasses import dataclass

from numba import njit

from ..component import param
from ..water import CP

STATES = ()


@dataclass(frozen=True)
class Params:
    T_set: float = param(45.0, "degC", "tap (mixed) temperature", 30, 70)
    T_cold: float = param(10.0, "degC", "cold-water temperature", 1, 30)


T_SET, T_COLD = range(2)


@njit(cache=True)
def draw(p, m_demand, T_hot):
    """Returns (m_hot from the storage, T_tap delivered, Q_missing [W] short of the set temperature)."""
    if m_demand <= 0.0:
        return 0.0, T_hot, 0.0
    T_set, T_cold = p[T_SET], p[T_COLD]
    if T_hot > T_set:
        m_hot = m_demand * (T_set - T_cold) / (T_hot - T_cold)
        return m_hot, T_set, 0.0
    return m_demand, T_hot, m_demand * CP * (T_set - max(T_hot, T_cold))
