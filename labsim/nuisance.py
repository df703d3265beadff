"""Model-form variations: how one installed rig differs from its datasheet, drawn per realisation.

A real lab's rig differs from the datasheet values a model is built from (sensors a few cm off,
sleeves that lag, a tank a little wider, generators with their own water and metal, bigger
headers, a coil not where the drawing puts it). A diagnosis that only holds when the truth has
the datasheet values does not hold in a lab. Realisation 0 is labsim's nominal rig (its recordings
are the ones the suite always made); realisation R >= 1 draws every quantity below uniformly
within its tolerance from a generator seeded with R, whatever the case, so the cases of one
realisation share one rig.

The columns file still states the datasheet values (a lab knows those, not the actual ones).

| key | nominal | drawn within | what |
|---|---|---|---|
| storage_sensor_heights | labsim's | +-3 cm each | immersion-sleeve heights in the 800 l tank [m] |
| dhw_sensor_heights | labsim's | +-3 cm each | the DHW tank's sensors [m] |
| port_top, port_bottom | 1.55, 0.08 m | +-3 cm | the tank's connection heights |
| storage_diameter_factor | 1 | 0.98 ... 1.02 | inner diameter / datasheet (the 800 l stand lower or higher) |
| storage_UA | 20 W/K | 15 ... 28 | standing loss where the case does not set it |
| well_tau | 15 s | 10 ... 60 s | sleeve lag of every pipe and tank sensor |
| pipe_tau | 1200 s | 900 ... 2400 s | cooling of a standing pipe at its sensor |
| plant_room | 20 degC | 17 ... 23 | the air the pipes cool toward |
| header_kg | 20 kg | 10 ... 30 | water in each header with its pipes |
| chp_C, boiler_C | 0 J/K | 40 ... 110 kJ/K, 12 ... 35 kJ/K | generator water and metal on the outlet |
| coil_top, coil_bottom | 1.21, 0.75 m | +-5 cm | the DHW coil's span |
| coil_UA | 640 W/K | 480 ... 800 | DHW coil heat transfer (x coil_factor of a case) |
| radiator_Q_N | 8778 W | +-15 % | radiator rating |
| radiator_mass | 120 kg | 80 ... 160 | water in the radiators and circuit pipes |
"""
from __future__ import annotations

import numpy as np

STORAGE_SENSOR_HEIGHTS = (0.12, 0.27, 0.42, 0.57, 0.72, 0.87, 1.02, 1.17, 1.32, 1.50)  # m, 1.63 m tank
DHW_SENSOR_HEIGHTS = {1: 0.10, 5: 0.70, 10: 1.40}  # m, 1.51 m tank
STORAGE_PORT_HEIGHTS = {"top": 1.55, "bottom": 0.08}  # m: where the switch's flows enter and leave

NOMINAL = {
    "storage_sensor_heights": STORAGE_SENSOR_HEIGHTS, "dhw_sensor_heights": DHW_SENSOR_HEIGHTS,
    "port_top": STORAGE_PORT_HEIGHTS["top"], "port_bottom": STORAGE_PORT_HEIGHTS["bottom"],
    "storage_diameter_factor": 1.0, "storage_UA": 20.0, "well_tau": 15.0, "pipe_tau": 1200.0,
    "plant_room": 20.0, "header_kg": 20.0, "chp_C": 0.0, "boiler_C": 0.0,
    "coil_top": 1.21, "coil_bottom": 0.75, "coil_UA": 640.0, "radiator_Q_N": 8778.0, "radiator_mass": 120.0,
}


def draw(realisation: int) -> dict:
    """The rig of one realisation (0: the nominal rig, exactly)."""
    if realisation == 0:
        return dict(NOMINAL)
    rng = np.random.default_rng(7919 * realisation)
    u = lambda lo, hi: float(rng.uniform(lo, hi))  # noqa: E731
    n = dict(NOMINAL)
    n["storage_sensor_heights"] = tuple(round(h + u(-0.03, 0.03), 4) for h in STORAGE_SENSOR_HEIGHTS)
    n["dhw_sensor_heights"] = {k: round(h + u(-0.03, 0.03), 4) for k, h in DHW_SENSOR_HEIGHTS.items()}
    n["port_top"] = STORAGE_PORT_HEIGHTS["top"] + u(-0.03, 0.03)
    n["port_bottom"] = max(0.02, STORAGE_PORT_HEIGHTS["bottom"] + u(-0.03, 0.03))
    n["storage_diameter_factor"] = u(0.98, 1.02)
    n["storage_UA"] = u(15.0, 28.0)
    n["well_tau"] = u(10.0, 60.0)
    n["pipe_tau"] = u(900.0, 2400.0)
    n["plant_room"] = u(17.0, 23.0)
    n["header_kg"] = u(10.0, 30.0)
    n["chp_C"] = u(40e3, 110e3)
    n["boiler_C"] = u(12e3, 35e3)
    n["coil_top"] = 1.21 + u(-0.05, 0.05)
    n["coil_bottom"] = 0.75 + u(-0.05, 0.05)
    n["coil_UA"] = u(480.0, 800.0)
    n["radiator_Q_N"] = 8778.0 * u(0.85, 1.15)
    n["radiator_mass"] = u(80.0, 160.0)
    return n


def public(n: dict) -> dict:
    """The drawn values as meta.json holds them (plain JSON types)."""
    out = dict(n)
    out["storage_sensor_heights"] = list(n["storage_sensor_heights"])
    out["dhw_sensor_heights"] = {str(k): v for k, v in n["dhw_sensor_heights"].items()}
    return out


__all__ = ["draw", "public", "NOMINAL", "STORAGE_SENSOR_HEIGHTS", "DHW_SENSOR_HEIGHTS", "STORAGE_PORT_HEIGHTS"]
