"""Pressure-driven hydraulics of a coupling point with two generators (`hydraulics = "pressure_driven"`).

Topology (the layout of the twin's hydraulic switch; R = return header is the pressure
reference, p_R = 0, S = supply header; one unknown pressure p_S):

    branch              from -> to   element                                       direction
    storage             R <-> S      tank + connection pipes, k_storage            both ways
    chp                 R -> S       CHP heat exchanger + pipes k_chp, internal    R -> S only
                                     pump (curve H0 n^2 - a m|m|), NO spring-      (flap in its
                                     loaded check valve, + its line k_chp_line     line)
    boiler              R -> S       speed-controlled boiler pump (flow source)    R -> S only
    consumers           S -> R       mixing-station primary + DHW charging pump    S -> R only
                                     (speed-controlled pumps = flow sources)

Both generators draw from the return header and feed the supply header, exactly as in the twin;
the truth differs only by pressure-driven flows. Why the idle CHP sees flow: when the consumers
draw more than the generators deliver, p_S falls below p_R and the deficit returns from R to S
through the storage AND through the idle CHP, shared by conductance; no spring-loaded check
valve holds the CHP branch closed against the small header pressure difference (a flap in its
line only stops reverse flow, S -> R). A running CHP pump is speed-controlled: the branch carries
max(own pump flow, the flow the header forces through the stopped pump).

Branch law (quadratic with a tiny laminar core so the derivative stays finite at zero flow):
    m = g(dp, k) = dp / sqrt(k |dp| + (k m0)^2)       ~ sign(dp) sqrt(|dp|/k) for |m| >> m0
A pump adds its head to dp: dp_eff = dp + H0 n^2, with the pump's internal resistance a included
in the branch resistance (a stopped wet-rotor pump is a plain resistance). Check valves: g = 0
for dp <= 0. Flow sources are given flows. The node balance at S is monotone in p_S (every
branch flow falls as p_S rises), solved by a safeguarded Newton iteration (bisection fallback),
warm-started from the previous step's pressure.

Pump curves (`pump_speed`) give the speed a speed-controlled pump needs for its flow against the
branch's pressure difference (reported as diagnostics; the pumps are sized so they never saturate).
All resistances are lumped, calibrated values (Pa/(kg/s)^2), not catalogue data: they are chosen so
that the idle CHP carries about a third of a heating deficit, the size the lab validation saw.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numba import njit

from ..component import param


@dataclass(frozen=True)
class NetworkParams:
    enabled: bool = param(True, "1", "pressure-driven network; false = the ideal switch (no forced flow)")
    k_storage: float = param(20000.0, "Pa/(kg/s)2", "storage and its connection pipes (R <-> S)", 1.0, 1e9)
    k_chp: float = param(70000.0, "Pa/(kg/s)2", "CHP branch: heat exchanger, pipes, stopped pump", 1.0, 1e9)
    k_chp_line: float = param(2000.0, "Pa/(kg/s)2", "CHP line into the supply header (with the flap)", 1.0, 1e9)
    m0: float = param(1e-4, "kg/s", "laminar core of the branch law (numerical regularisation)", 1e-8, 1e-2)
    chp_pump_H0: float = param(4000.0, "Pa", "CHP internal pump: head at zero flow, full speed", 0.0, 1e6)
    chp_pump_a: float = param(6000.0, "Pa/(kg/s)2", "CHP internal pump: curve coefficient (part of k_chp)", 0.0, 1e9)
    boiler_pump_H0: float = param(40000.0, "Pa", "boiler pump: head at zero flow, full speed", 0.0, 1e6)
    boiler_pump_a: float = param(2.0e5, "Pa/(kg/s)2", "boiler pump: curve coefficient", 0.0, 1e9)
    boiler_k: float = param(1.5e5, "Pa/(kg/s)2", "boiler heat exchanger and pipes", 0.0, 1e9)
    mixer_pump_H0: float = param(40000.0, "Pa", "mixing-station pump: head at zero flow", 0.0, 1e6)
    mixer_pump_a: float = param(2.0e5, "Pa/(kg/s)2", "mixing-station pump: curve coefficient", 0.0, 1e9)
    mixer_k: float = param(3.0e5, "Pa/(kg/s)2", "radiator circuit", 0.0, 1e9)
    dhw_pump_H0: float = param(40000.0, "Pa", "DHW charging pump: head at zero flow", 0.0, 1e6)
    dhw_pump_a: float = param(1.0e5, "Pa/(kg/s)2", "DHW charging pump: curve coefficient", 0.0, 1e9)
    dhw_k: float = param(1.5e5, "Pa/(kg/s)2", "DHW charging coil and pipes", 0.0, 1e9)


(ENABLED, K_STORAGE, K_CHP, K_CHP_LINE, M0, CHP_PUMP_H0, CHP_PUMP_A, BOILER_PUMP_H0,
 BOILER_PUMP_A, BOILER_K, MIXER_PUMP_H0, MIXER_PUMP_A, MIXER_K, DHW_PUMP_H0, DHW_PUMP_A,
 DHW_K) = range(16)
N_NET = 16
assert len(fields(NetworkParams)) == N_NET

# solution vector layout (float64, len N_SOL): pressures and branch flows [Pa, kg/s]
(X_PS, X_M_STORAGE, X_M_CHP, X_ITER, X_RES) = range(5)
N_SOL = 5


def pack(params: NetworkParams) -> np.ndarray:
    return np.array([float(getattr(params, f.name)) for f in fields(params)], dtype=np.float64)


@njit(cache=True, inline="always")
def branch(dp, k, m0):
    """Flow and d(flow)/d(dp) of a quadratic resistance with a laminar core (both directions)."""
    D = k * abs(dp) + k * k * m0 * m0
    s = math.sqrt(D)
    return dp / s, (0.5 * k * abs(dp) + k * k * m0 * m0) / (D * s)


@njit(cache=True, inline="always")
def check_branch(dp, k, m0):
    """As `branch`, but a check valve blocks flow against the direction (dp <= 0)."""
    if dp <= 0.0:
        return 0.0, 0.0
    return branch(dp, k, m0)


@njit(cache=True)
def pump_speed(m, dp_against, H0, a, k):
    """Relative speed a pump needs for flow m against a pressure rise dp_against, in a branch of
    resistance k: H0 n^2 = dp_against + (a + k) m^2 (affinity law). Returns >= 0 (> 1: saturated)."""
    if m <= 0.0 or H0 <= 0.0:
        return 0.0
    need = dp_against + (a + k) * m * m
    return math.sqrt(need / H0) if need > 0.0 else 0.0


@njit(cache=True)
def flows(pS, p, chp_fixed, m_chp_fixed, n_chp, sol):
    """Storage and CHP flows at p_S (p_R = 0); fills sol; returns (F_S, dF_S/dp_S) without the
    flow sources (boiler in, consumers out)."""
    m0 = p[M0]
    m_st, d_st = branch(0.0 - pS, p[K_STORAGE], m0)
    if chp_fixed:
        m_c, d_c = m_chp_fixed, 0.0
    else:
        m_c, d_c = check_branch(0.0 - pS + p[CHP_PUMP_H0] * n_chp * n_chp, p[K_CHP] + p[K_CHP_LINE], m0)
    sol[X_PS] = pS
    sol[X_M_STORAGE] = m_st
    sol[X_M_CHP] = m_c
    return m_st + m_c, -d_st - d_c


@njit(cache=True)
def solve(p, m_boiler, m_consumers, chp_fixed, m_chp_fixed, n_chp, pS0, sol):
    """Pressure p_S and branch flows for given flow sources (boiler R->S, consumers S->R) and the
    CHP branch either pressure-driven with its pump at relative speed n_chp (chp_fixed False) or
    a fixed flow m_chp_fixed. Node balance S: storage + chp + boiler - consumers = 0 (R follows).
    Fills sol (see X_*); returns the residual [kg/s]."""
    src = m_boiler - m_consumers
    # bracket: F(p) = flows(p) + src is strictly decreasing in p (the storage branch)
    lo, hi = -1.0, 1.0
    for _ in range(80):
        F, _d = flows(lo, p, chp_fixed, m_chp_fixed, n_chp, sol)
        if F + src > 0.0:
            break
        lo *= 4.0
    for _ in range(80):
        F, _d = flows(hi, p, chp_fixed, m_chp_fixed, n_chp, sol)
        if F + src < 0.0:
            break
        hi *= 4.0
    pS = min(max(pS0, lo), hi)
    res = 1e300
    it = 0
    for it in range(100):
        F, d = flows(pS, p, chp_fixed, m_chp_fixed, n_chp, sol)
        F += src
        res = abs(F)
        if res < 1e-13:
            break
        if F > 0.0:
            lo = pS
        else:
            hi = pS
        nxt = pS - F / d if d < 0.0 else 0.5 * (lo + hi)
        if not (lo < nxt < hi) or not math.isfinite(nxt):
            nxt = 0.5 * (lo + hi)
        pS = nxt
        if hi - lo <= 1e-12 * (1.0 + abs(pS)):
            break
    F, d = flows(pS, p, chp_fixed, m_chp_fixed, n_chp, sol)
    res = abs(F + src)
    sol[X_ITER] = it + 1
    sol[X_RES] = res
    return res
