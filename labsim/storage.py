"""labsim storage tank: an explicit finite-volume model with first-order upwind advection.

Per layer i (0 = bottom) the energy E_i = M c T_i changes in one step dt by
  * port inflows (mass s_i at T_in) and outflows (o_i at T_i),
  * the vertical flow through the interface above layer i, F_i = sum_{k<=i} (s_k - o_k) (upward
    positive), carrying the upwind layer's temperature (flux form: what leaves one layer enters
    the next, so advection conserves energy to round-off),
  * conduction between neighbours, k_int (T_{i+1} - T_i), k_int = lambda_eff A / dz,
  * losses UA/n (T_i - T_env) per layer, and the heat of an immersed coil;
then buoyancy: an inverted profile (a layer warmer than the one above) is mixed at once by
convective adjustment (pooling adjacent layers into blocks of their mean until the profile rises
monotonically), which conserves energy exactly. Stable while dt x (outflow of a layer) < M.

An inflow may spread over several layers next to its port (an inlet plume, `spread_layers`): the
water then enters each of them in equal shares. A coil is a heat exchanger through a span of
layers: the fluid enters at the top layer of the span and passes each layer's segment with
T_out = T_layer + (T_in - T_layer) exp(-UA_seg / (m c)); the coil holds no water of its own.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

CP = 4180.0


@njit(cache=True)
def _advect(T, M, dt, src_m, src_e, sink_m):
    """One explicit upwind step of the layer temperatures T in place; returns nothing."""
    n = T.shape[0]
    E = M * T
    F = 0.0
    for i in range(n):
        E[i] += dt * (src_e[i] - sink_m[i] * T[i])
        F += src_m[i] - sink_m[i]  # flow through the interface above layer i (upward > 0)
        if i < n - 1:
            if F > 0.0:
                flux = F * T[i]
            else:
                flux = F * T[i + 1]
            E[i] -= dt * flux
            E[i + 1] += dt * flux
    for i in range(n):
        T[i] = E[i] / M


@njit(cache=True)
def _exchange(T, M_cp, dt, k_int, ua_layer, T_env, q_extra):
    """Conduction between neighbours, losses and extra heat [W per layer]; returns the loss [W]."""
    n = T.shape[0]
    dE = np.zeros(n)
    loss = 0.0
    for i in range(n):
        q = ua_layer * (T[i] - T_env)
        loss += q
        dE[i] += q_extra[i] - q
        if i < n - 1:
            c = k_int * (T[i + 1] - T[i])
            dE[i] += c
            dE[i + 1] -= c
    for i in range(n):
        T[i] += dt * dE[i] / M_cp
    return loss


@njit(cache=True)
def _buoyancy(T):
    """Convective adjustment: mix inversions into blocks of their mean (equal layer masses)."""
    n = T.shape[0]
    sums = np.zeros(n)
    counts = np.zeros(n, dtype=np.int64)
    top = -1
    for i in range(n):
        top += 1
        sums[top] = T[i]
        counts[top] = 1
        while top > 0 and sums[top] / counts[top] < sums[top - 1] / counts[top - 1]:
            sums[top - 1] += sums[top]
            counts[top - 1] += counts[top]
            top -= 1
    k = 0
    for b in range(top + 1):
        mean = sums[b] / counts[b]
        for _ in range(counts[b]):
            T[k] = mean
            k += 1


class Tank:
    """A vertical cylindrical tank of `n` equal layers; heights in m above the bottom."""

    def __init__(self, volume: float, height: float, n: int, UA_loss: float, T_env: float,
                 T_bottom: float, T_top: float, lambda_eff: float = 1.0):
        self.n, self.height = n, height
        self.M = volume * 1000.0 / n              # kg per layer
        self.dz = height / n
        area = volume / height
        self.k_int = lambda_eff * area / self.dz  # W/K between neighbours
        self.ua_layer = UA_loss / n
        self.T_env = T_env
        self.z = (np.arange(n) + 0.5) * self.dz
        self.T = np.linspace(T_bottom, T_top, n)
        self.loss = 0.0                           # W, last step
        self._zero = np.zeros(n)

    def layer(self, height: float) -> int:
        return min(self.n - 1, max(0, int(height / self.dz)))

    def spread(self, height: float, layers: int, downward: bool) -> np.ndarray:
        """Weights of an inflow at `height` spread over `layers` layers below (or above) the port."""
        w = np.zeros(self.n)
        i = self.layer(height)
        span = range(max(0, i - layers + 1), i + 1) if downward else range(i, min(self.n, i + layers))
        for k in span:
            w[k] = 1.0
        return w / w.sum()

    def at(self, height: float) -> float:
        """Temperature at a height (linear between layer centres)."""
        return float(np.interp(height, self.z, self.T))

    def step(self, dt: float, inflows, outflows, q_extra=None) -> list[float]:
        """inflows: [(weights, m kg/s, T_in)], outflows: [(layer, m)]; masses must balance.
        Returns the outflow temperatures (the outlet layers before the step)."""
        out_T = [float(self.T[i]) for i, _ in outflows]
        src_m = np.zeros(self.n)
        src_e = np.zeros(self.n)
        sink = np.zeros(self.n)
        for w, m, T_in in inflows:
            if m > 0.0:
                src_m += w * m
                src_e += w * (m * T_in)
        for i, m in outflows:
            sink[i] += m
        if src_m.any() or sink.any():
            _advect(self.T, self.M, dt, src_m, src_e, sink)
        self.loss = _exchange(self.T, self.M * CP, dt, self.k_int, self.ua_layer, self.T_env,
                              self._zero if q_extra is None else q_extra)
        _buoyancy(self.T)
        return out_T

    def energy(self) -> float:
        """Stored heat [J] relative to 0 degC."""
        return float(self.T.sum() * self.M * CP)


def coil_heat(T: np.ndarray, layers: range, UA: float, m: float, T_in: float) -> tuple[np.ndarray, float]:
    """(heat per layer [W], outlet temperature) of a coil entering at the last index of `layers`."""
    q = np.zeros(T.shape[0])
    if m <= 1e-9:
        return q, T_in
    seg = UA / len(layers)
    f = math.exp(-seg / (m * CP))
    t = T_in
    for i in reversed(layers):
        t_out = T[i] + (t - T[i]) * f
        q[i] = m * CP * (t - t_out)
        t = t_out
    return q, t


__all__ = ["Tank", "coil_heat", "CP"]
