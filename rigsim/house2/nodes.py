"""Small numerical helpers of rigsim's house-2 core (house 3's too): a bilinear table lookup, the
implicit update of one node of a flow chain, a coil's segments in series, and the heat held by the
hydronic system."""
from __future__ import annotations

import numpy as np
from numba import njit

from .layout import (
    CP, N_MASS, N_NODES, N_ROOM, P_FL_C_SEG, P_M_CELL, P_SOL_C_SEG,
)


@njit(cache=True, inline="always")
def _bracket(x, xs):
    """The interval i of grid xs that holds x and x's weight in it (edge values held beyond)."""
    n = xs.size
    if x <= xs[0]:
        return 0, 0.0
    if x >= xs[n - 1]:
        return n - 2, 1.0
    i = 0
    while xs[i + 1] < x:
        i += 1
    return i, (x - xs[i]) / (xs[i + 1] - xs[i])


@njit(cache=True)
def interp2(x, y, xs, ys, Z):
    """Bilinear in a grid Z[len(xs), len(ys)], edge values held beyond the grid."""
    i, wx = _bracket(x, xs)
    j, wy = _bracket(y, ys)
    a = Z[i, j] + wy * (Z[i, j + 1] - Z[i, j])
    b = Z[i + 1, j] + wy * (Z[i + 1, j + 1] - Z[i + 1, j])
    return a + wx * (b - a)


@njit(cache=True, inline="always")
def adv(nodes, C_nodes, i, m, T_in, Q, UA, T_env, dt):
    """chain() on nodes[i] in place; returns its loss rate [W]."""
    nodes[i], loss = chain(nodes[i], C_nodes[i], m, T_in, Q, UA, T_env, dt)
    return loss


@njit(cache=True, inline="always")
def chain(T, C, m, T_in, Q, UA, T_env, dt):
    """Implicit update of one chain node: returns (T_new, loss rate [W] at T_new)."""
    Tn = (C * T + dt * (m * CP * T_in + Q + UA * T_env)) / (C + dt * (m * CP + UA))
    return Tn, UA * (Tn - T_env)


@njit(cache=True)
def stored_heat(P, nodes, C_nodes, Tt, Tc, Tf):
    """Heat held by every node of the hydronic system [J above 0 degC] (building nodes excluded)."""
    e = P[P_M_CELL] * CP * np.sum(Tt) + P[P_SOL_C_SEG] * np.sum(Tc) + P[P_FL_C_SEG] * np.sum(Tf)
    for i in range(N_NODES):
        if i != N_ROOM and i != N_MASS:
            e += C_nodes[i] * nodes[i]
    return e


@njit(cache=True)
def coil_chain(Tc, lo, hi, coil_W, Tt, m, T_in, UA_seg, C_seg, Qt, dt):
    """Segments lo ... hi-1 of Tc, a tank coil in series from its inlet (flow m [kg/s] at T_in),
    each implicit against the tank cells it lies over (weights coil_W[segment, cell]); adds their
    heat to Qt [W per cell] and returns the coil's outlet temperature."""
    n = Tt.size
    T_prev = T_in
    for kk in range(lo, hi):
        Tb = 0.0
        for j in range(n):
            Tb += coil_W[kk, j] * Tt[j]
        Tn = ((C_seg * Tc[kk] + dt * (m * CP * T_prev + UA_seg * Tb))
              / (C_seg + dt * (m * CP + UA_seg)))
        q = UA_seg * (Tn - Tb)
        for j in range(n):
            Qt[j] += coil_W[kk, j] * q
        Tc[kk] = Tn
        T_prev = Tn
    return T_prev
