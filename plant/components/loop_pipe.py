"""A pipe of a unit's loop to the outdoor air (the solar collector's supply and return lines).

Physics in words
----------------
A pipe of conductance UA to the outdoor air at T_air, that water enters at T_in with flow m:
* holding no water (C = 0): the steady exchanger, outlet T_air + (T_in - T_air) exp(-UA / (m cp)),
  loss m cp (T_in - T_out); standing (m = 0) it neither delivers nor loses;
* holding water of heat capacity C: one mixed node, C dT/dt = m cp (T_in - T) - UA (T - T_air),
  advanced exactly over the step (its mean temperature is the outlet's), loss UA (T_mean - T_air);
  standing, its water cools towards T_air with the time constant C / UA, and the next run pushes
  that cooled water to the consumer first. One node smears the front a plug of water would keep
  (its delay is C / (m cp) as a time constant, not a dead time); its energy is exact:
      m cp (T_in - T_mean) h = loss h + C (T_end - T_start).

The steady form is written so that UA = 0 returns T_in bit for bit. Used by
plant/components/solar_collector.py (`UA_loop`, `V_loop`); tested in tests/plant/test_solar.py.
"""
from __future__ import annotations

import math

from numba import njit

from ..water import CP


@njit(cache=True)
def line(T, T_air, m, UA):
    """Outlet of the steady pipe (no water held) entered at T with flow m."""
    if m <= 0.0:
        return T
    return T - (T - T_air) * (-math.expm1(-UA / (m * CP)))


@njit(cache=True)
def step(h, x, k, C, UA, T_in, T_air, m):
    """Advance the pipe over h; x[k] is its water's temperature (used only when C > 0). Returns
    (outlet temperature, mean loss to the outdoor air [W]) over the step."""
    if C <= 0.0:
        T_out = line(T_in, T_air, m, UA)
        return T_out, m * CP * (T_in - T_out)
    T0 = x[k]
    mc = m * CP if m > 0.0 else 0.0
    beta = mc + UA
    if beta <= 0.0:
        return T0, 0.0
    T_inf = (mc * T_in + UA * T_air) / beta
    r = beta * h / C
    T1 = T_inf + (T0 - T_inf) * math.exp(-r)
    T_mean = T_inf + (T0 - T_inf) * (-math.expm1(-r) / r) if r > 1e-12 else 0.5 * (T0 + T1)
    x[k] = T1
    return T_mean, UA * (T_mean - T_air)
