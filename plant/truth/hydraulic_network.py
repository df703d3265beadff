"""Pressure-driven hydraulic network of house 1's generator side (the "truth" plant).

Topology (three pressure nodes; R = return header is the pressure reference, p_R = 0):

    S  supply header (hot)          R  return header (cold)
    J  common coupling point of the generators: the CHP outlet joins the boiler's return line

    branch              from -> to   element                                       direction
    storage             R -> S       tank + connection pipes, k_storage            both ways
    chp                 R -> J       CHP heat exchanger + pipes k_chp, internal    both ways
                                     pump (curve H0 n^2 - a m|m|), NO check valve  (no check valve)
    link                R -> J       boiler return pipe with the boiler pump, k_link R -> J only
                                     (+ stopped pump and boiler when idle), check valve
    chp_line            J -> S       CHP supply line into the header, k_chp_line,  J -> S only
                                     check valve
    boiler              J -> S       speed-controlled boiler pump (flow source)    J -> S only
    consumers           S -> R       mixing-station primary + DHW charging pump    S -> R only
                                     (speed-controlled pumps = flow sources)

Why the idle CHP sees flow: when the heating circuit draws more than the generators deliver,
the deficit returns from R to S through the storage AND through the parallel path
R -> (CHP || link) -> J -> S, shared by conductance; nothing stops it in the CHP branch.
Why the boiler sucks extra flow through the CHP: the boiler pump draws from J; p_J falls below
p_R and both the link and the CHP branch feed J, so the CHP carries a share of the boiler flow
even when its own pump would deliver less (its speed control loses authority).

Branch law (quadratic with a tiny laminar core so the Jacobian stays finite at zero flow):
    m = g(dp, k) = dp / sqrt(k |dp| + (k m0)^2)       ~ sign(dp) sqrt(|dp|/k) for |m| >> m0
A pump adds its head to dp: dp_eff = dp + H0 n^2, with the pump's internal resistance a included
in the branch resistance (a stopped wet-rotor pump is a plain resistance). Check valves: g = 0
for dp <= 0. Flow sources are given flows. The two node balances (S, J) are solved by a damped
2x2 Newton iteration (the network is monotone: every branch flow increases with its driving
pressure difference, so the residual is the gradient of a convex co-content and Newton with
backtracking converges); warm-started from the previous step's pressures.

Pump curves (`pump_speed`) give the speed a speed-controlled pump needs for its flow against the
branch's pressure difference (reported as diagnostics; the pumps are sized so they never saturate).
All resistances are lumped, calibrated values (Pa/(kg/s)^2), not catalogue data: they are chosen so
that the idle CHP carries 20-30 % of a typical heating flow, the size the lab validation saw.
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
    k_link: float = param(3500.0, "Pa/(kg/s)2", "boiler return pipe from R to the coupling point J", 1.0, 1e9)
    k_chp_line: float = param(2000.0, "Pa/(kg/s)2", "line from J into the supply header", 1.0, 1e9)
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
    V_junction: float = param(0.005, "m3", "water content of the coupling point J (pipes)", 0.0005, 1.0)


(ENABLED, K_STORAGE, K_CHP, K_LINK, K_CHP_LINE, M0, CHP_PUMP_H0, CHP_PUMP_A, BOILER_PUMP_H0,
 BOILER_PUMP_A, BOILER_K, MIXER_PUMP_H0, MIXER_PUMP_A, MIXER_K, DHW_PUMP_H0, DHW_PUMP_A, DHW_K,
 V_JUNCTION) = range(18)
N_NET = 18
assert len(fields(NetworkParams)) == N_NET

# solution vector layout (float64, len N_SOL): pressures and branch flows [Pa, kg/s]
(X_PS, X_PJ, X_M_STORAGE, X_M_CHP, X_M_LINK, X_M_CHP_LINE, X_ITER, X_RES) = range(8)
N_SOL = 8


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
def flows(pS, pJ, p, chp_fixed, m_chp_fixed, n_chp, sol, k_link):
    """Branch flows at pressures (pS, pJ), p_R = 0; fills sol; returns (F_S, F_J, dFS/dpS,
    dFS/dpJ, dFJ/dpS, dFJ/dpJ) without the flow sources. k_link: the link's resistance now."""
    m0 = p[M0]
    m_st, d_st = branch(0.0 - pS, p[K_STORAGE], m0)
    if chp_fixed:
        m_c, d_c = m_chp_fixed, 0.0
    else:
        m_c, d_c = branch(0.0 - pJ + p[CHP_PUMP_H0] * n_chp * n_chp, p[K_CHP], m0)
    m_l, d_l = check_branch(0.0 - pJ, k_link, m0)
    m_js, d_js = check_branch(pJ - pS, p[K_CHP_LINE], m0)
    sol[X_PS] = pS
    sol[X_PJ] = pJ
    sol[X_M_STORAGE] = m_st
    sol[X_M_CHP] = m_c
    sol[X_M_LINK] = m_l
    sol[X_M_CHP_LINE] = m_js
    # F_S = storage in + chp_line in (+ boiler - consumers, added by the caller)
    F_S = m_st + m_js
    F_J = m_c + m_l - m_js
    dSS = -d_st - d_js
    dSJ = d_js
    dJS = d_js
    dJJ = -d_c - d_l - d_js
    return F_S, F_J, dSS, dSJ, dJS, dJJ


@njit(cache=True)
def solve(p, m_boiler, m_consumers, chp_fixed, m_chp_fixed, n_chp, pS0, pJ0, sol):
    """Pressures and branch flows for given flow sources (boiler J->S, consumers S->R) and the CHP
    branch either pressure-driven with its pump at relative speed n_chp (chp_fixed False) or a
    fixed flow m_chp_fixed. Node balances: S: storage + chp_line + boiler - consumers = 0;
    J: chp + link - chp_line - boiler = 0. Fills sol (see X_*); returns the residual [kg/s]."""
    # The boiler's pump sits in its return pipe (the link): stopped, it and the boiler's heat
    # exchanger add their resistance, so an idle-side short circuit passes mainly the idle CHP.
    k_link = p[K_LINK] + (p[BOILER_PUMP_A] + p[BOILER_K] if m_boiler <= 0.0 else 0.0)
    pS, pJ = pS0, pJ0
    res = 1e300
    it = 0
    for it in range(60):
        F_S, F_J, a, b, c, d = flows(pS, pJ, p, chp_fixed, m_chp_fixed, n_chp, sol, k_link)
        F_S += m_boiler - m_consumers
        F_J -= m_boiler
        res = abs(F_S) + abs(F_J)
        if res < 1e-12:
            break
        det = a * d - b * c
        if det == 0.0 or not math.isfinite(det):
            # a degenerate Jacobian: nudge J towards R (the link opens)
            pJ = 0.5 * pJ - 1.0
            continue
        dS = -(d * F_S - b * F_J) / det
        dJ = -(-c * F_S + a * F_J) / det
        lam = 1.0
        for _ in range(40):
            tS, tJ, _a, _b, _c, _d = flows(pS + lam * dS, pJ + lam * dJ, p, chp_fixed, m_chp_fixed,
                                           n_chp, sol, k_link)
            tS += m_boiler - m_consumers
            tJ -= m_boiler
            if abs(tS) + abs(tJ) < res:
                break
            lam *= 0.5
        pS += lam * dS
        pJ += lam * dJ
    F_S, F_J, a, b, c, d = flows(pS, pJ, p, chp_fixed, m_chp_fixed, n_chp, sol, k_link)
    res = abs(F_S + m_boiler - m_consumers) + abs(F_J - m_boiler)
    sol[X_ITER] = it + 1
    sol[X_RES] = res
    return res
