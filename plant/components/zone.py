"""Living zone of the building: a two-node (air + envelope mass) thermal model with gains.

Physics: the room node (air and furniture, capacity C_room) exchanges heat with the outdoor air
through windows, leakage and ventilation (H_direct) and with the envelope mass node (H_mass);
the mass node (capacity C_mass) loses heat to outdoors through the opaque walls (H_envelope).
Gains into the room node: radiator heat, people (presence x persons x 110 W), household
electricity (all of it ends as heat), half of the solar gain (the other half heats the mass).
Solar gain through windows = A_solar x (f_dir x beam + f_dif x diffuse horizontal irradiance).

Applicability: heating-season dynamics of a whole dwelling (hours to days). It lumps the
original's three-zone building with unheated roof and cellar into H values. Calibration: the
reference's best-effort envelope (typology class 1995-2001: ~460 W/K) is inconsistent with the
house's own radiator design (8.78 kW at 60/45/21 degC): with it the house cannot hold 21 degC below
about -8 degC and needs 101 kWh/(m2 a). We calibrate the total conductance to ~300 W/K so that the
radiators at full flow cover the design load at -16 degC (Munich) with internal gains: 54 kWh/(m2 a)
of space heat for 2021, and the room recovers from the night set-back within ~1 h on a -4 degC
day. Both figures come from `load_house("house1").run(...)`; recalibrate against recordings.

| parameter   | unit | meaning |
|-------------|------|---------|
| C_room      | J/K  | air + furniture + inner surfaces |
| C_mass      | J/K  | envelope and slabs |
| H_direct    | W/K  | windows, leakage and ventilation (calibrated, see above) |
| H_mass      | W/K  | room <-> mass surface coupling |
| H_envelope  | W/K  | opaque walls to outdoors |
| A_solar     | m2   | effective solar aperture g*A_win*(1-0.4)*(1-0.4) = 0.6*58.5*0.36 |
| persons     | 1    | residents |
Validated by tests/plant/test_zone.py (steady state = gains/H, energy balance).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, Knob, indices, param

STATES = ("T_room", "T_mass")


@dataclass(frozen=True)
class Params:
    C_room: float = param(12.0e6, "J/K", "room air, furniture and inner surfaces", 1e5, 1e9)
    C_mass: float = param(80.0e6, "J/K", "envelope and floor slabs", 1e6, 1e10)
    H_direct: float = param(180.0, "W/K", "room to outdoor air: windows, leakage, ventilation", 0, 1e4)
    H_mass: float = param(2000.0, "W/K", "room to envelope mass", 1, 1e5)
    H_envelope: float = param(130.0, "W/K", "envelope mass to outdoor air", 0, 1e4)
    A_solar: float = param(12.6, "m2", "effective solar aperture of the windows", 0, 500)
    f_dir: float = param(0.45, "1", "share of horizontal beam irradiance reaching the windows", 0, 2)
    f_dif: float = param(0.5, "1", "share of horizontal diffuse irradiance reaching the windows", 0, 2)
    persons: float = param(6.0, "1", "residents", 0, 100)
    P_person: float = param(110.0, "W", "sensible heat per person at home", 0, 300)
    T_day: float = param(21.0, "degC", "room set-point by day", 5, 30)
    T_night: float = param(18.0, "degC", "room set-point at night (night reduction)", 5, 30)
    night_start: float = param(23.0, "h", "night reduction starts (local time)", 0, 24)
    night_end: float = param(7.0, "h", "night reduction ends (local time)", 0, 24)
    T_init: float = param(21.0, "degC", "initial room and mass temperature", -10, 40)


# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


def initial_state(params: Params) -> np.ndarray:
    return np.array([params.T_init, params.T_init], dtype=np.float64)


@njit(cache=True)
def setpoint(p, tau):
    """Room set-point [degC] at local time tau [s since the year start]."""
    hour = (tau % 86400.0) / 3600.0
    start, end = p[P.night_start], p[P.night_end]
    if start > end:
        night = hour >= start or hour < end
    else:
        night = start <= hour < end
    return p[P.T_night] if night else p[P.T_day]


@njit(cache=True)
def step(dt, x, p, T_out, E_dir, E_dif, presence, P_el_household, Q_heating):
    """Advance the zone by dt; returns (Q_gains_internal, Q_solar, Q_loss) [W]."""
    T_r, T_m = x[X.T_room], x[X.T_mass]
    Q_int = presence * p[P.persons] * p[P.P_person] + P_el_household
    Q_sol = p[P.A_solar] * (p[P.f_dir] * E_dir + p[P.f_dif] * E_dif)
    Q_rm = p[P.H_mass] * (T_r - T_m)
    Q_loss = p[P.H_direct] * (T_r - T_out) + p[P.H_envelope] * (T_m - T_out)
    x[X.T_room] = T_r + dt * (Q_heating + Q_int + 0.5 * Q_sol - Q_rm - p[P.H_direct] * (T_r - T_out)) / p[P.C_room]
    x[X.T_mass] = T_m + dt * (Q_rm + 0.5 * Q_sol - p[P.H_envelope] * (T_m - T_out)) / p[P.C_mass]
    return Q_int, Q_sol, Q_loss


class Kind(ComponentKind):
    """The living zone: weather and gains from the profiles, heat from its emitters."""

    name = "zone"
    Params = Params
    role = "zone"
    UNMEASURED = ("T_set", "Q_flow_gains", "Q_flow_solar")
    KNOBS = (Knob("H_direct", "W/K", "room-to-outdoor conductance (ventilation, leakage): the room "
                  "temperature and, through it, the emitter's emission", rel=0.10, rank=2),)

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit(self, c, inst):
        x, p = c.views(inst)
        mod = c.module(__name__)
        T_set, Q_int, Q_sol, Q_loss = (c.var(v) for v in ("T_set_room", "Q_int", "Q_sol", "Q_zloss"))
        c.values[f"{inst.name}.T_set"] = T_set
        c.emit("setpoints", f"{T_set} = {mod}.setpoint({p}, tau)")
        heat = c.heat_to.get(inst.name) or ["0.0"]
        c.emit("rooms", f"{Q_int}, {Q_sol}, {Q_loss} = {mod}.step(h, {x}, {p}, T_air, E_dir, E_dif, presence, "
                        f"P_hh, {' + '.join(heat)})")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('T_room', 'degC', 'living-zone temperature')} = {x}[{X.T_room}]",
               f"{sig('T_set', 'degC', 'room set-point (with night reduction)')} = {T_set}",
               f"{sig('T_mass', 'degC', 'envelope mass temperature')} = {x}[{X.T_mass}]",
               f"{sig('Q_flow_gains', 'W', 'internal gains (people and household electricity)')} = {Q_int}",
               f"{sig('Q_flow_solar', 'W', 'solar gains')} = {Q_sol}")
