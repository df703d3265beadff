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
+- (SLEEVE_TOL_M / H + GEOMETRY_TOL x z). The top and bottom sensors have no sensor beyond them:
where one sits within its sleeve's tolerance of the port at its end (or beyond it), moved toward
the tank's end it reads toward the end layer (storage.T_top / T_bot, at the end layer's centre),
a piece of its own. That is where a sensor sits above the top port (rigsim realisation 3: 2 cm
above it, 2 cm below it by the drawing): in still water that a hot inflow reaches at once and a
cold one not at all, a reading that rises with the port and holds through a fall, which the
gradient from below reads as a lag (the one-way "lag", docs/diagnose.md). Only the sleeve's
tolerance counts there: a tank's diameter moves its ports with its sensors. A sensor further
from its port cannot reach the still water (labsim's top sensor, 5 cm below its port: given the
piece, the still water took part of a true 300 s lag on it, 47 % -> 28 % of its residual
removed). The nominal twin and every candidate get the same freedom, so it cancels in their
comparison; a sensor candidate on a storage sensor is fitted with its own shift again
(fit.fit_signal), so a real offset is not taken by the shift (the shift's reading follows the
gradient, an offset does not).

Tolerances (not tuned on a suite; the rig description's, docs/lab/house1-rig.md §5, a lab's usual
installation tolerance): SLEEVE_TOL_M = 3 cm per sleeve, GEOMETRY_TOL = 0.04 (a +-2 % diameter).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

SLEEVE_TOL_M = 0.03
GEOMETRY_TOL = 0.04
SENSOR = ".T_sensor_"


class Tank(NamedTuple):
    height: float       # [m]
    layers: int         # the replayed scheme's layer count
    top: float | None   # the top and bottom ports' relative heights (None: no port there known)
    bottom: float | None


def points_of(spec, storage: str) -> list:
    """The coupling points of the declaration `spec` that feed `storage` at their ports."""
    return [j for j in spec.instances.values() if j.options.get("storage") == storage and "storage_top" in j.options]


def tanks(spec, lab: dict) -> dict:
    """Every storage of the declaration `spec` by name -> Tank: its ports a coupling point's
    (storage_top / storage_bottom [m], where the overrides `lab` put them)."""
    out = {}
    for i in spec.instances.values():
        if i.kind != "storage":
            continue
        H = float(i.params.height)
        pt = points_of(spec, i.name)
        at = {e: lab.get(f"{pt[0].name}.storage_{e}", pt[0].options.get(f"storage_{e}")) if pt else None
              for e in ("top", "bottom")}
        out[i.name] = Tank(H, int(i.params.n_layers), *(None if at[e] is None else float(at[e]) / H
                                                        for e in ("top", "bottom")))
    return out


@dataclass(frozen=True)
class Piece:
    g: np.ndarray       # the simulated vertical gradient over this piece [K per tank height]
    lo: float           # the shifts it covers (relative, + up)
    hi: float


@dataclass(frozen=True)
class HeightFit:
    shift: float        # the reading's move, in tank heights (relative, + up)
    tol: float          # the tolerance it was held within (relative)
    g: np.ndarray       # the gradient of the piece the shift lies on [K per tank height]
    pieces: tuple = ()  # the reading's pieces (Piece): one, or two for a sensor at the tank's end

    def __post_init__(self):
        if not self.pieces:  # one piece: the gradient over the whole tolerance
            object.__setattr__(self, "pieces", (Piece(self.g, -self.tol, self.tol),))

    def public(self, H: float) -> dict:
        return {"shift_m": round(self.shift * H, 4), "tolerance_m": round(self.tol * H, 4),
                "at_bound": bool(abs(self.shift) >= self.tol * (1 - 1e-9) and self.tol > 0)}


def gradients(rec, out: np.ndarray, cols: dict, tanks: dict | None = None) -> dict:
    """{measured storage sensor: (gradient per sample [K per tank height], relative height,
    gradient toward the tank's end layer or None, that layer's relative height)} from the replay
    rows `out` (the simulated sensors on either side; one side at the ends, and the end layer
    beyond it where the sensor sits within its sleeve's tolerance of that end's port (tanks:
    storage -> Tank) and the replay has the layer)."""
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
        y = out[:, cols[s]]
        g = (out[:, cols[f"{arr}{SENSOR}{hi}"]] - out[:, cols[f"{arr}{SENSOR}{lo}"]]) / (z(hi) - z(lo))
        g_end, z_end = None, None
        tank = (tanks or {}).get(arr)
        end = f"{arr}.T_top" if hi == k else f"{arr}.T_bot" if lo == k else None
        port = None if tank is None else tank.top if hi == k else tank.bottom
        up = 1 if hi == k else -1
        if end in cols and port is not None and (port - z(k)) * up * tank.height <= SLEEVE_TOL_M:
            z_end = 1 - 0.5 / tank.layers if hi == k else 0.5 / tank.layers
            if (z_end - z(k)) * up > 0:
                g_end = np.nan_to_num((out[:, cols[end]] - y) / (z_end - z(k)))
        grads[s] = (np.nan_to_num(g), z(k), g_end, z_end)
    return grads


def pieces_of(g, z, g_end, z_end, tol) -> tuple:
    """The reading's pieces within +-tol: the gradient at the sensor over the whole tolerance, or,
    with an end layer beyond it, the gradient from the inside toward the inside and the one to
    the end layer up to it."""
    if g_end is None:
        return (Piece(g, -tol, tol),)
    if z_end > z:
        return Piece(g, -tol, 0.0), Piece(g_end, 0.0, min(tol, z_end - z))
    return Piece(g_end, -min(tol, z - z_end), 0.0), Piece(g, 0.0, tol)


def best_shift(e: np.ndarray, g: np.ndarray, m: np.ndarray, lo: float, hi: float) -> tuple[float, float]:
    """The shift within [lo, hi] whose reading change s x g best removes the residual e on mask m
    -> (shift, the squares it removes)."""
    m = m & np.isfinite(e)
    den = float(g[m] @ g[m])
    if den <= 0.0 or m.sum() < 10:
        return 0.0, 0.0
    ge = float(g[m] @ e[m])
    s = float(np.clip(ge / den, lo, hi))
    return s, 2 * s * ge - s * s * den


def best_place(e: np.ndarray, m: np.ndarray, pieces) -> tuple[float, np.ndarray]:
    """The shift over the pieces that best removes the residual e on mask m -> (shift, its
    piece's gradient)."""
    best = None
    for p in pieces:
        s, gain = best_shift(e, p.g[:len(e)], m[:len(e)], p.lo, p.hi)
        if best is None or gain > best[0]:
            best = (gain, s, p.g)
    return best[1], best[2]


def placed(meas, y, m, hf):
    """The reading y moved within its sensor's height tolerance to fit meas on mask m (hf None:
    not a storage sensor, y as it is)."""
    if hf is None:
        return y
    s, g = best_place(meas[:len(y)] - y, m[:len(y)], hf.pieces)
    return y + s * g[:len(y)]


def apply(rec, out: np.ndarray, cols: dict, n: int, tanks: dict, t_fit: float | None) -> dict:
    """Move the measured storage sensors' columns of the replay rows `out` (first n samples)
    within their tolerance, each shift fitted on the samples up to t_fit (None: no shift).
    tanks: storage -> Tank. -> {signal: HeightFit}."""
    t = rec.time[:n]
    fit = np.zeros(n, bool) if t_fit is None else (t <= t_fit)
    if rec.valid is not None:
        fit &= rec.valid[:n]
    fits = {}
    for s, (g, z, g_end, z_end) in gradients(rec, out[:n], cols, tanks).items():
        tank = tanks.get(s.rpartition(SENSOR)[0])
        if tank is None or not tank.height:
            continue
        H = tank.height
        tol = SLEEVE_TOL_M / H + GEOMETRY_TOL * z
        pieces = pieces_of(g, z, g_end, z_end, tol)
        y = out[:n, cols[s]]
        shift, gs = best_place(rec.data[s][:n] - y, fit & np.isfinite(y), pieces)
        out[:n, cols[s]] = y + shift * gs
        fits[s] = HeightFit(shift, tol, gs, pieces)
    return fits


__all__ = ["apply", "best_shift", "best_place", "placed", "gradients", "pieces_of", "points_of", "tanks",
           "HeightFit", "Piece", "Tank", "SLEEVE_TOL_M", "GEOMETRY_TOL"]
