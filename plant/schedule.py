"""Time splitting shared by every plant: internal steps of at most H_MAX, and the span plan that
replays a command table (midpoint switches, cuts at whole minutes)."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

H_MAX = 5.0  # s, largest internal step (header volume 10 l, flows up to ~1 kg/s)


@njit(cache=True)
def n_steps(dt):
    """Internal steps for a span of dt seconds: equal steps of at most H_MAX."""
    return max(1, int(math.ceil(dt / H_MAX - 1e-9)))


@njit(cache=True)
def _row(plan, k, a, b, rec):
    """Row k of a plan: the span a..b as n equal steps of h (n_steps; n = 0 for a span of no
    length), sample rec (-1: none) recorded at its end. -> k + 1."""
    n = n_steps(b - a) if b > a else 0
    plan[k, 0], plan[k, 1], plan[k, 2], plan[k, 3] = a, (b - a) / n if n > 0 else 0.0, n, rec
    return k + 1


@njit(cache=True)
def _span(plan, k, a, b, rec):
    """The span a..b, cut at the last whole minute inside: the profiles (DHW draws,
    electricity) change on minutes and a step samples them at its start."""
    m = math.floor(b / 60.0) * 60.0
    if a + 1e-6 < m < b - 1e-6:
        k = _row(plan, k, a, m, -1)
        a = m
    return _row(plan, k, a, b, rec)


@njit(cache=True)
def drive_steps(times, cmd):
    """The rows (t0, h, n, recorded sample or -1) the generated advance steps through to replay
    a command table from t = 0: row i of the table holds from sample i to i + 1, a change is
    applied at the midpoint (the samples cannot tell when it happened)."""
    n = times.shape[0]
    plan = np.empty((4 * n, 4))
    k = _span(plan, 0, 0.0, times[0], 0)
    for i in range(1, n):
        t0, t1 = times[i - 1], times[i]
        same = True
        for j in range(cmd.shape[1]):
            if cmd[i - 1, j] != cmd[i, j]:
                same = False
        if same:
            k = _span(plan, k, t0, t1, i)
        else:
            tm = 0.5 * (t0 + t1)
            k = _span(plan, k, t0, tm, -1)
            k = _span(plan, k, tm, t1, i)
    return plan[:k]


def run_steps(t0: float, h: float, n: int) -> np.ndarray:
    """The one row of a run: n steps of h from t0, no sample recorded at its end."""
    return np.array([[t0, h, float(n), -1.0]])


HOLD, LINEAR = 0, 1


@njit(cache=True)
def apply_bindings(t, h, bind, s):
    """Bound inputs follow their time series: s[idx[j]] = series j at the step (HOLD: the last
    sample at or before the step's start; LINEAR: interpolated at the step's midpoint). Before
    the first sample a series holds its first value, after the last its last; NaN keeps the
    previous value (a gap in a recording)."""
    bt, bv, idx, mode = bind
    n = bt.shape[0]
    # the series share one time grid (House.bind): one search per mode and step, not per series
    # (a replay binds nine; their searches were a twentieth of its step)
    i_hold = i_lin = -2  # -2: not searched yet
    for j in range(idx.shape[0]):
        if mode[j] == LINEAR:
            tt = t + 0.5 * h
            if i_lin == -2:
                i_lin = np.searchsorted(bt, tt, side="right") - 1
            i = i_lin
        else:
            tt = t
            if i_hold == -2:
                i_hold = np.searchsorted(bt, tt, side="right") - 1
            i = i_hold
        if i < 0:
            v = bv[0, j]
        elif i >= n - 1 or mode[j] != LINEAR:
            v = bv[min(i, n - 1), j]
        else:
            w = (tt - bt[i]) / (bt[i + 1] - bt[i])
            v = bv[i, j] * (1.0 - w) + bv[i + 1, j] * w
        if v == v:
            s[idx[j]] = v
