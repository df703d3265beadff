"""The tanks of rigsim: 1-D finite-volume columns of equal cells (advection upwind, conduction
between neighbours, losses, coil heat), a buoyancy step that re-orders unstable cells (a warmer
cell rises to its level of neutral buoyancy without mixing on the way), the DHW tank's charging
coil, and the lookups the core shares (tables, sensor heights). House 2's core uses the same
kernels (tank_multi: its storage with five port pairs)."""
from __future__ import annotations

from numba import njit

from .layout import CP


@njit(cache=True)
def interp1(x, xp, fp):
    n = xp.size
    if x <= xp[0]:
        return fp[0]
    if x >= xp[n - 1]:
        return fp[n - 1]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xp[mid] <= x:
            lo = mid
        else:
            hi = mid
    w = (x - xp[lo]) / (xp[hi] - xp[lo])
    return fp[lo] + w * (fp[hi] - fp[lo])


@njit(cache=True)
def at_height(T, pos):
    """Temperature at a position given in cell units (cell j's centre at j + 0.5)."""
    x = pos - 0.5
    n = T.size
    if x <= 0.0:
        return T[0]
    if x >= n - 1:
        return T[n - 1]
    j = int(x)
    w = x - j
    return T[j] + w * (T[j + 1] - T[j])


@njit(cache=True, inline="always")
def _cell_rate(T, j, F, Fup, e, kcond, UA, T_env, extra_Q, cp):
    """Heat rate [W] into cell j of a column and its standing loss [W]: e [kg/s * degC] is the
    enthalpy the cell's own inflows and outflows bring, to which the upwind advection over its
    lower face (upward mass flux F) and its upper face (Fup) is added; then the heat put into
    the cell (extra_Q[j], coil), the loss to T_env and conduction between neighbours; cp the
    water's heat capacity [J/(kg K)]."""
    n = T.size
    if F > 0.0:
        e += F * T[j - 1]
    else:
        e += F * T[j]
    if j < n - 1:
        if Fup > 0.0:
            e -= Fup * T[j]
        else:
            e -= Fup * T[j + 1]
    ql = UA[j] * (T[j] - T_env)
    q = cp * e + extra_Q[j] - ql
    if j > 0:
        q += kcond * (T[j - 1] - T[j])
    if j < n - 1:
        q += kcond * (T[j + 1] - T[j])
    return q, ql


@njit(cache=True, inline="always")
def _settle(T, M, dt, dE, cp):
    """Advance the column's cells (mass M each) by the heat rates dE over dt, then the buoyancy
    step: insertion sort, warmest on top (equal cell masses: energy exactly conserved)."""
    n = T.size
    c = dt / (M * cp)
    for j in range(n):
        T[j] += dE[j] * c
    for j in range(1, n):
        v = T[j]
        k = j - 1
        while k >= 0 and T[k] > v:
            T[k + 1] = T[k]
            k -= 1
        T[k + 1] = v


@njit(cache=True)
def tank_step(T, M, dt, src_w, src_flow, T_in, sink_idx, kcond, UA, T_env, extra_Q, dE, cp=CP):
    """Advance one tank column by dt. Returns the heat lost to the room [W].

    src_flow [kg/s] enters at T_in, distributed over the cells by src_w (sum 1); the same mass
    leaves from cell sink_idx. extra_Q [W] is heat put into each cell (coil); cp the water's
    heat capacity (house 1's by default).
    """
    n = T.size
    F = 0.0  # upward mass flux across the lower face of cell j
    loss = 0.0
    for j in range(n):
        s = src_flow * src_w[j]
        r = src_flow if j == sink_idx else 0.0
        Fup = F + s - r
        q, ql = _cell_rate(T, j, F, Fup, s * T_in - r * T[j], kcond, UA, T_env, extra_Q, cp)
        dE[j] = q
        loss += ql
        F = Fup
    _settle(T, M, dt, dE, cp)
    return loss


@njit(cache=True)
def tank_multi(T, M, dt, S, SE, R, kcond, UA, T_env, extra_Q, dE, cp=CP):
    """One step of a column with any number of ports: inflows S [kg/s] carrying SE
    [kg/s * degC] and outflows R [kg/s] per cell (sum S = sum R), extra_Q [W] per cell.
    Returns the standing loss [W]; cp as for tank_step."""
    n = T.size
    F = 0.0
    loss = 0.0
    for j in range(n):
        Fup = F + S[j] - R[j]
        q, ql = _cell_rate(T, j, F, Fup, SE[j] - R[j] * T[j], kcond, UA, T_env, extra_Q, cp)
        dE[j] = q
        loss += ql
        F = Fup
    _settle(T, M, dt, dE, cp)
    return loss


@njit(cache=True, inline="always")
def coil_exchange(Td, Tc, coil_W, UA_seg, C_seg, m_dhw, T_in, dt, Qd, Qc):
    """The DHW coil's segments from the inlet (top) down, from the states at the start of the
    step: Qd[j] [W] the heat into tank cell j, Qc[k] the temperature change of segment k."""
    nd = Td.size
    nc = Tc.size
    for j in range(nd):
        Qd[j] = 0.0
    T_prev = T_in
    for k in range(nc):
        Tt = 0.0
        for j in range(nd):
            Tt += coil_W[k, j] * Td[j]
        Qk = UA_seg * (Tc[k] - Tt)
        for j in range(nd):
            Qd[j] += coil_W[k, j] * Qk
        Qc[k] = (m_dhw * CP * (T_prev - Tc[k]) - Qk) * dt / C_seg
        T_prev = Tc[k]
