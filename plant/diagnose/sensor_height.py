"""Where a storage sensor sits is known to a tolerance: every replay places it within it.

A lab knows its tank sensors' heights from the drawing, not to the centimetre: a sleeve sits a
few cm from where the drawing has it, and a tank whose diameter differs by 2 % from the datasheet
holds its volume over a height 4 % different, so a sensor at relative height z sits up to 4 % x z
off in the volume below it. In a stratified tank such a shift is a reading off by the local
gradient times the shift: a few tenths of a K, more while a thermocline passes. The twin placed
exactly where the columns file says reads that as a sensor offset on a rig that has none.

So every replay moves each measured storage sensor's reading within its tolerance: the reading at
z + s is the twin's reading at z plus s times the simulated vertical gradient there (from the
simulated sensors next to it), s fitted by least squares on the training samples and held within
+- (SLEEVE_TOL_M / H + GEOMETRY_TOL x z). The nominal twin and every candidate get the same
freedom, so it cancels in their comparison; a sensor candidate on a storage sensor is fitted with
its own shift again (fit.fit_signal), so a real offset is not taken by the shift (the shift's
reading follows the gradient, an offset does not).

Tolerances (not tuned on a suite; the rig description's, docs/lab/house1-rig.md §5, a lab's usual
installation tolerance): SLEEVE_TOL_M = 3 cm per sleeve, GEOMETRY_TOL = 0.04 (a +-2 % diameter).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SLEEVE_TOL_M = 0.03
GEOMETRY_TOL = 0.04
SENSOR = ".T_sensor_"


@dataclass(frozen=True)
class HeightFit:
    shift: float        # the reading's move, in tank heights (relative, + up)
    tol: float          # the tolerance it was held within (relative)
    g: np.ndarray       # the simulated vertical gradient at the sensor [K per tank height]

    def public(self, H: float) -> dict:
        return {"shift_m": round(self.shift * H, 4), "tolerance_m": round(self.tol * H, 4),
                "at_bound": bool(abs(self.shift) >= self.tol * (1 - 1e-9) and self.tol > 0)}


def gradients(rec, out: np.ndarray, cols: dict) -> dict:
    """{measured storage sensor: (gradient per sample [K per tank height], relative height)} from
    the replay rows `out` (the simulated sensors on either side; one side at the ends)."""
    grads = {}
    for s in cols:
        arr, sep, k = s.rpartition(SENSOR)
        if not sep or not k.isdigit() or not rec.has(s):
            continue
        k = int(k)
        sims = {int(x.rpartition(SENSOR)[2]) for x in cols if x.startswith(arr + SENSOR)}
        n = max(10, max(sims))

        def z(i):
            return rec.heights.get(f"{arr}{SENSOR}{i}", (i - 0.5) / n)
        lo = k - 1 if (k - 1) in sims else k
        hi = k + 1 if (k + 1) in sims else k
        if lo == hi or z(hi) <= z(lo):
            continue
        g = (out[:, cols[f"{arr}{SENSOR}{hi}"]] - out[:, cols[f"{arr}{SENSOR}{lo}"]]) / (z(hi) - z(lo))
        grads[s] = (np.nan_to_num(g), z(k))
    return grads


def best_shift(e: np.ndarray, g: np.ndarray, m: np.ndarray, tol: float) -> float:
    """The shift within +-tol whose reading change s x g best removes the residual e on mask m."""
    m = m & np.isfinite(e)
    den = float(g[m] @ g[m])
    if den <= 0.0 or m.sum() < 10:
        return 0.0
    return float(np.clip(float(g[m] @ e[m]) / den, -tol, tol))


def placed(meas, y, m, hf):
    """The reading y moved within its sensor's height tolerance to fit meas on mask m (hf None:
    not a storage sensor, y as it is)."""
    if hf is None:
        return y
    g = hf.g[:len(y)]
    return y + best_shift(meas[:len(y)] - y, g, m[:len(y)], hf.tol) * g


def apply(rec, out: np.ndarray, cols: dict, n: int, heights_m: dict, t_fit: float | None) -> dict:
    """Move the measured storage sensors' columns of the replay rows `out` (first n samples)
    within their tolerance, each shift fitted on the samples up to t_fit (None: no shift).
    heights_m: storage -> its height [m]. -> {signal: HeightFit}."""
    t = rec.time[:n]
    fit = np.zeros(n, bool) if t_fit is None else (t <= t_fit)
    if rec.valid is not None:
        fit &= rec.valid[:n]
    fits = {}
    for s, (g, z) in gradients(rec, out[:n], cols).items():
        H = heights_m.get(s.rpartition(SENSOR)[0])
        if not H:
            continue
        tol = SLEEVE_TOL_M / H + GEOMETRY_TOL * z
        y = out[:n, cols[s]]
        shift = best_shift(rec.data[s][:n] - y, g, fit & np.isfinite(y), tol)
        out[:n, cols[s]] = y + shift * g
        fits[s] = HeightFit(shift, tol, g)
    return fits


__all__ = ["apply", "best_shift", "placed", "gradients", "HeightFit", "SLEEVE_TOL_M", "GEOMETRY_TOL"]
