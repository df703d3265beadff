"""Bounded searches over a parameter's range (on its log scale where the parameter says so):
a coarse grid then bounded Brent (scalar_search), a coordinate pass (descent), and whether a
fitted value ended on a bound (at_bound). Shared by the calibration and the candidates' fits."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar


def to_u(p, v):
    return math.log(v) if p.log else v


def from_u(p, u):
    return min(max(math.exp(u) if p.log else u, p.lo), p.hi)


def scalar_search(f, p, n_grid=6, maxiter=10):
    lo, hi = to_u(p, p.lo), to_u(p, p.hi)
    grid = np.linspace(lo, hi, n_grid)
    vals = [f(from_u(p, u)) for u in grid]
    k = int(np.argmin(vals))
    a, b = grid[max(0, k - 1)], grid[min(n_grid - 1, k + 1)]
    res = minimize_scalar(lambda u: f(from_u(p, u)), bounds=(a, b), method="bounded",
                          options={"xatol": (hi - lo) * 2e-3, "maxiter": maxiter})
    best_u, best_v = (res.x, res.fun) if res.fun <= vals[k] else (grid[k], vals[k])
    return from_u(p, best_u), float(best_v), n_grid + int(res.nfev)


def at_bound(p, v) -> bool:
    """Whether a fitted value ends on a bound of its search range (in the search's scale): the
    data asked for more than the parameter may give."""
    lo, hi, u = to_u(p, p.lo), to_u(p, p.hi), to_u(p, max(v, p.lo) if p.log else v)
    return bool(min(u - lo, hi - u) <= 2e-3 * (hi - lo))


def descent(F, params, theta, idx, maxiter=6, n_grid=3):
    """One coordinate pass: each parameter in idx by a coarse grid + bounded Brent over its whole
    (narrow) range, the others held. -> (theta, cost, evaluations)."""
    theta = list(theta)
    J = F(theta)
    nfev = 1
    for i in idx:
        p = params[i]

        def f(v, i=i):
            th = list(theta)
            th[i] = v
            return F(th)

        v, Jv, k = scalar_search(f, p, n_grid=n_grid, maxiter=maxiter)
        nfev += k
        if Jv < J:
            theta[i], J = v, Jv
    return theta, J, nfev
