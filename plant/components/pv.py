"""Photovoltaic generator: electric power from the irradiance on its plane and its peak power.

Physics in words
----------------
A simple performance-ratio model (as in PVGIS-style yield estimates):
    P_el = P_peak x G_plane / 1000 W/m2 x PR x (1 + gamma (T_cell - 25 degC)),   P_el >= 0,
    T_cell = T_air + (T_NOCT - 20 degC) x G_plane / 800 W/m2   (NOCT model),
G_plane being the irradiance on the module plane from the weather's horizontal beam and diffuse
(plant/sun.py: sun position at the step's local standard time, isotropic sky, ground
reflection). The performance ratio PR holds every loss but the temperature derate (inverter,
wiring, soiling, mismatch, reflection); P_peak is the array's rating at STC (1000 W/m2, 25 degC).
The inverter is not clipped: the output never exceeds P_peak x PR in Munich's weather anyway
(PR <= 1, G_plane <= ~1100 W/m2, cells above 25 degC at such irradiance).

Ledger: only `el` (P_el x h, produced is positive); the sunlight is not counted as fuel and no
heat enters the water. The house's `generator_losses` (fuel - el - heat) therefore falls by the
PV yield.

Parameters (SI)
---------------
| name | unit | meaning |
|---|---|---|
| P_peak | W | rated power at STC (SF2, SF3: 10 kWp) |
| PR | 1 | performance ratio without the temperature derate (0.86) |
| gamma | 1/K | power temperature coefficient (-0.004, crystalline silicon) |
| T_NOCT | degC | nominal operating cell temperature (45) |
| tilt, azimuth | deg | module plane (35 deg, 180 = south) |
| latitude, longitude | deg | site (Munich) |
| albedo | 1 | ground reflectance |

Applicability: a fixed, unshaded array; no low-irradiance efficiency loss, no snow, no
clipping. Data: the upstream houses use a GreenCity PV block whose equations are not available
(reference §0.4); these are textbook values. Validated by tests/plant/test_pv.py.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .. import sun
from ..component import Kind as ComponentKind, indices, pack, param


@dataclass(frozen=True)
class Params:
    P_peak: float = param(10000.0, "W", "rated power at STC (1000 W/m2, 25 degC)", 0.0, 1e8)
    PR: float = param(0.86, "1", "performance ratio without the temperature derate", 0.0, 1.0)
    gamma: float = param(-0.004, "1/K", "power temperature coefficient", -0.02, 0.0)
    T_NOCT: float = param(45.0, "degC", "nominal operating cell temperature", 20.0, 80.0)
    tilt: float = param(35.0, "deg", "tilt from the horizontal", 0.0, 90.0)
    azimuth: float = param(180.0, "deg", "azimuth of the plane's normal (90 east, 180 south, 270 west)", 0.0, 360.0)
    latitude: float = param(48.14, "deg", "site latitude (north positive)", -90.0, 90.0)
    longitude: float = param(11.58, "deg", "site longitude (east positive; clock is CET = 15 deg E)", -180.0, 180.0)
    albedo: float = param(0.2, "1", "ground reflectance", 0.0, 1.0)


STATES = ("E_el",)
# positions in the packed parameters and the state vector, from the declarations
PAR = indices(Params)
X = indices(STATES)


@njit(cache=True)
def power(p, G, T_air):
    """(P_el [W], T_cell [degC]) at plane irradiance G [W/m2] and outdoor air T_air."""
    T_cell = T_air + (p[PAR.T_NOCT] - 20.0) * G / 800.0
    P = p[PAR.P_peak] * G / 1000.0 * p[PAR.PR] * (1.0 + p[PAR.gamma] * (T_cell - 25.0))
    return max(P, 0.0), T_cell


class Kind(ComponentKind):
    """A PV array; emits itself (irradiance from the weather, power into the ledger)."""

    name = "pv"
    Params = Params
    role = "component"

    def initial_state(self, inst):
        return np.zeros(len(STATES))

    def emit(self, c, inst):
        x, p = c.state(inst, self.initial_state(inst)), c.param(inst, pack(inst.params))
        beam, dif, cos_t = sun.emit_plane(c, inst, p, PAR)
        mod = c.module(__name__)
        P, T_cell = c.var("P_pv"), c.var("T_cell")
        c.emit("hydraulics",
               f"{P}, {T_cell} = {mod}.power({p}, {beam} + {dif}, T_air)",
               f"{x}[{X.E_el}] += {P} * h")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('P_el', 'W', 'electric power produced (AC)')} = {P}",
               f"{sig('E_el', 'J', 'electric energy produced since the start')} = {x}[{X.E_el}]",
               f"{sig('G_plane', 'W/m2', 'irradiance on the module plane (beam + diffuse + ground)')} = {beam} + {dif}",
               f"{sig('T_cell', 'degC', 'cell temperature (NOCT model)')} = {T_cell}",
               f"{c.ledger_entry(inst, 'el')} += {P} * h")
